"""A line-protocol device peer for the driver tests: one TCP client at a time on 127.0.0.1.

Shared plumbing only (sockets, lines, the test's instructions); each device's words live in
its own file, written from that device's public documentation, never from calstand's command
sets.

stdout: one JSON object per line: {"port": N} first, then {"connected": k} per connection,
{"cmd": "..."} per command received, and what the device module reports (e.g. {"set": 23.5}).
stdin (from the test), one instruction per line:
  drop            close the client's connection (the device stays up and accepts the next)
  alarm [ARG]     raise an alarm (the device decides what ARG means)
  clear           clear the alarm
  refuse [WORDS]  refuse setting commands from now on
  accept          accept them again
  air V           the air temperature is V degC
  garble          answer the next command with line noise
  quit            end
"""
import json
import selectors
import socket
import sys


def report(**fields):
    print(json.dumps(fields), flush=True)


class Device:
    """Override handle(); the state the tests steer is here."""

    def __init__(self):
        self.air = 23.0
        self.setpoint = 23.0
        self.running = False
        self.alarm = None  # None or the device-specific argument of "alarm"
        self.refusal = None  # None or the words of "refuse"
        self.garble = False  # the next reply is line noise

    def handle(self, command):
        """Returns the reply line (without terminator), or None for no reply."""
        raise NotImplementedError

    def instruct(self, words):
        if not words:
            return
        what, arg = words[0], " ".join(words[1:])
        if what == "alarm":
            self.alarm = arg or "1"
        elif what == "clear":
            self.alarm = None
        elif what == "refuse":
            self.refusal = arg or None
            if self.refusal is None:
                self.refusal = self.default_refusal()
        elif what == "accept":
            self.refusal = None
        elif what == "air":
            self.air = float(arg)
        elif what == "garble":
            self.garble = True

    def default_refusal(self):
        return "refused"


def serve(device, reply_terminator=b"\r\n", separators=b"\r\n"):
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(("127.0.0.1", 0))
    listener.listen(4)
    report(port=listener.getsockname()[1])
    sel = selectors.DefaultSelector()
    sel.register(listener, selectors.EVENT_READ, "listen")
    sel.register(sys.stdin, selectors.EVENT_READ, "stdin")
    client = None
    pending = b""
    connections = 0
    while True:
        for key, _ in sel.select(timeout=60):
            if key.data == "listen":
                conn, _ = listener.accept()
                if client is not None:
                    sel.unregister(client)
                    client.close()
                client = conn
                pending = b""
                connections += 1
                sel.register(client, selectors.EVENT_READ, "client")
                report(connected=connections)
            elif key.data == "stdin":
                line = sys.stdin.readline()
                if not line or line.strip() == "quit":
                    return
                words = line.split()
                if words and words[0] == "drop":
                    if client is not None:
                        sel.unregister(client)
                        client.close()
                        client = None
                    report(dropped=connections)
                else:
                    device.instruct(words)
                    report(instructed=line.strip())
            else:
                data = client.recv(4096)
                if not data:
                    sel.unregister(client)
                    client.close()
                    client = None
                    continue
                pending += data
                while True:
                    cut = [i for i in (pending.find(bytes([s])) for s in separators) if i >= 0]
                    if not cut:
                        break
                    end = min(cut)
                    raw, pending = pending[:end], pending[end + 1:]
                    if not raw:
                        continue
                    command = raw.decode("latin-1")
                    report(cmd=command)
                    reply = device.handle(command)
                    if reply is not None and device.garble:
                        device.garble = False
                        reply = "#~%&"
                    if reply is not None:
                        client.sendall(reply.encode("latin-1") + reply_terminator)
