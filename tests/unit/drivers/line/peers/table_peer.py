"""A simulated two-axis rate table behind a TCP line server, shared by the controller peers.

Only the mechanics live here (angles moving at a rate limit, rate mode, sine, stop, interlocks
and faults) and the harness (TCP, stdin control); each controller's words are in its own
peer file, written from that controller's public material. Nothing here reads calstand's
command sets.

Harness: the server listens on 127.0.0.1 (a free port) and prints "port N" on stdout. Lines
on stdin steer it, each answered "ok <line>" on stdout once done:
  drop                  close every client connection (the server keeps listening)
  interlock AXIS WHY    open AXIS's interlock (latched; the cause is gone at once)
  hold AXIS WHY         open AXIS's interlock and keep its cause present
  release AXIS          the cause of AXIS's interlock is gone (it stays latched)
  fault AXIS TEXT       AXIS faults with TEXT (latched until the controller's reset)
  quit                  end
"""

import math
import socket
import sys
import threading
import time


def wrap_180(deg):
    w = math.fmod(deg + 180.0, 360.0)
    if w < 0.0:
        w += 360.0
    return w - 180.0


class Axis:
    """One axis: mode is rest, position, rate, sine or off (servo off / faulted)."""

    def __init__(self):
        self.angle = 0.0  # unwrapped [deg]
        self.rate = 0.0  # [deg/s]
        self.mode = "rest"
        self.target = 0.0  # position demand, wrapped [deg]
        self.max_rate = 100.0  # the controller's profile limits
        self.max_accel = 500.0
        self.demand_rate = 0.0
        self.sine_amplitude = 0.0
        self.sine_frequency = 0.0
        self.sine_phase_deg = 0.0
        self.sine_centre = 0.0
        self.sine_t0 = 0.0
        self.servo = True
        self.interlock_open = False
        self.interlock_why = ""
        self.cause_present = False
        self.fault = ""  # latched fault text; empty: none

    def usable(self):
        return self.servo and not self.interlock_open and not self.fault

    def halt(self):
        self.rate = 0.0
        self.mode = "off"

    def advance(self, dt, now):
        if self.mode == "off":
            self.rate = 0.0
            return
        if self.mode == "position":
            error = wrap_180(self.target - self.angle)
            step = self.max_rate * dt
            if abs(error) <= step:
                self.angle += error
                self.rate = 0.0
            else:
                self.angle += math.copysign(step, error)
                self.rate = math.copysign(self.max_rate, error)
            return
        if self.mode == "sine":
            w = 2.0 * math.pi * self.sine_frequency
            t = now - self.sine_t0
            ph = math.radians(self.sine_phase_deg)
            self.angle = self.sine_centre + self.sine_amplitude * math.sin(w * t + ph)
            self.rate = self.sine_amplitude * w * math.cos(w * t + ph)
            return
        goal = self.demand_rate if self.mode == "rate" else 0.0
        dv = self.max_accel * dt
        if abs(goal - self.rate) <= dv:
            self.rate = goal
        else:
            self.rate += math.copysign(dv, goal - self.rate)
        self.angle += self.rate * dt

    def start_sine(self, amplitude, frequency, phase_deg, now):
        self.sine_amplitude = amplitude
        self.sine_frequency = frequency
        self.sine_phase_deg = phase_deg
        self.sine_centre = self.angle
        self.sine_t0 = now
        self.mode = "sine"


class Table:
    def __init__(self, names):
        self.lock = threading.RLock()
        self.axes = {n: Axis() for n in names}
        self.t = time.monotonic()

    def update(self):
        now = time.monotonic()
        dt = now - self.t
        self.t = now
        for a in self.axes.values():
            a.advance(dt, now)
        return now


class Server:
    """Serves `handler(line) -> list of reply strings` (each sent with `ending`) over TCP.
    `split` is the set of bytes that end an incoming line."""

    def __init__(self, table, handler, ending=b"\n", split=b"\r\n"):
        self.table = table
        self.handler = handler
        self.ending = ending
        self.split = split
        self.clients = []
        self.clients_lock = threading.Lock()
        self.listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.listener.bind(("127.0.0.1", 0))
        self.listener.listen(8)

    def port(self):
        return self.listener.getsockname()[1]

    def serve_client(self, conn):
        buffer = b""
        try:
            while True:
                data = conn.recv(4096)
                if not data:
                    break
                buffer += data
                while True:
                    cut = min((i for i in (buffer.find(c) for c in self.split) if i >= 0),
                              default=-1)
                    if cut < 0:
                        break
                    line, buffer = buffer[:cut], buffer[cut + 1:]
                    text = line.decode("latin-1").strip()
                    if not text:
                        continue
                    with self.table.lock:
                        self.table.update()
                        replies = self.handler(text)
                    out = b"".join(r.encode("latin-1") + self.ending for r in replies)
                    if out:
                        conn.sendall(out)
        except OSError:
            pass
        finally:
            with self.clients_lock:
                if conn in self.clients:
                    self.clients.remove(conn)
            try:
                conn.close()
            except OSError:
                pass

    def accept_loop(self):
        while True:
            try:
                conn, _ = self.listener.accept()
            except OSError:
                return
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            with self.clients_lock:
                self.clients.append(conn)
            threading.Thread(target=self.serve_client, args=(conn,), daemon=True).start()

    def drop(self):
        with self.clients_lock:
            for c in self.clients:
                try:
                    c.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
                c.close()
            self.clients.clear()


def run(table, handler, ending=b"\n", split=b"\r\n"):
    server = Server(table, handler, ending, split)
    threading.Thread(target=server.accept_loop, daemon=True).start()
    print("port %d" % server.port(), flush=True)
    for raw in sys.stdin:
        words = raw.split()
        if not words:
            continue
        cmd = words[0]
        with table.lock:
            table.update()
            axis = table.axes.get(words[1]) if len(words) > 1 else None
            rest = " ".join(words[2:])
            if cmd == "drop":
                server.drop()
            elif cmd in ("interlock", "hold") and axis is not None:
                axis.interlock_open = True
                axis.interlock_why = rest
                axis.cause_present = cmd == "hold"
                axis.halt()
            elif cmd == "release" and axis is not None:
                axis.cause_present = False
            elif cmd == "fault" and axis is not None:
                axis.fault = rest or "fault"
                axis.halt()
            elif cmd == "quit":
                server.drop()
                server.listener.close()
                print("ok " + raw.strip(), flush=True)
                return
        print("ok " + raw.strip(), flush=True)
    server.drop()
