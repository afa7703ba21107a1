"""A Cincinnati Sub-Zero EZT-570i/S stand-in, written from the controller's User Communication
Reference Manual (section 2.4, control registers), not from calstand's map: the independent
peer the csz-ezt570 map is tested against (tests/unit/drivers/modbus/csz_ezt570_test.cpp).
Plain sockets and struct, no Modbus library.

Registers (zero-based protocol addresses, holding): 22 chamber manual event word (bit 0 =
chamber on), 55..58 alarm status words (bit-oriented), 60 loop 1 setpoint and 61 loop 1
process value (signed, one implied decimal: 235 = 23.5 degC). Anything else is answered with
exception 2 (illegal data address); functions other than 3, 6 and 16 with exception 1.

Output (stdout, one line each, flushed):
  port <N>                            once listening on 127.0.0.1
  {"write": a, "values": [...]}       after every client write
Input (stdin): "pv <degC>", "alarm <register> <word>", "drop" (closes every client connection);
end of input stops the peer.
"""
import json
import socket
import struct
import sys
import threading

CHAMBER_EVENTS = 22
ALARMS = (55, 56, 57, 58)
SETPOINT = 60
PROCESS_VALUE = 61

registers = {CHAMBER_EVENTS: 0, SETPOINT: 250, PROCESS_VALUE: 235}
registers.update({a: 0 for a in ALARMS})
lock = threading.Lock()
clients = []


def say(line):
    sys.stdout.write(line + "\n")
    sys.stdout.flush()


def tenths(degc):
    return struct.unpack(">H", struct.pack(">h", int(round(degc * 10))))[0]


def read_exactly(conn, n):
    data = b""
    while len(data) < n:
        chunk = conn.recv(n - len(data))
        if not chunk:
            raise ConnectionError("closed")
        data += chunk
    return data


def answer(pdu):
    """The response PDU to one request PDU."""
    function = pdu[0]
    if function == 3:
        start, count = struct.unpack(">HH", pdu[1:5])
        with lock:
            if not all(a in registers for a in range(start, start + count)):
                return bytes([function | 0x80, 2])
            words = [registers[a] for a in range(start, start + count)]
        return bytes([3, 2 * count]) + struct.pack(">%dH" % count, *words)
    if function in (6, 16):
        if function == 6:
            start, value = struct.unpack(">HH", pdu[1:5])
            values = [value]
        else:
            start, count, _ = struct.unpack(">HHB", pdu[1:6])
            values = list(struct.unpack(">%dH" % count, pdu[6:6 + 2 * count]))
        writable = (CHAMBER_EVENTS, SETPOINT)
        if not all(a in writable for a in range(start, start + len(values))):
            return bytes([function | 0x80, 2])
        with lock:
            for i, v in enumerate(values):
                registers[start + i] = v
        say(json.dumps({"write": start, "values": values}))
        return pdu[:5] if function == 6 else struct.pack(">BHH", 16, start, len(values))
    return bytes([function | 0x80, 1])


def serve(conn):
    try:
        while True:
            transaction, protocol, length, unit = struct.unpack(">HHHB", read_exactly(conn, 7))
            pdu = read_exactly(conn, length - 1)
            reply = answer(pdu)
            conn.sendall(struct.pack(">HHHB", transaction, protocol, len(reply) + 1, unit) + reply)
    except (ConnectionError, OSError, struct.error):
        pass
    finally:
        conn.close()


def accept(listener):
    while True:
        try:
            conn, _ = listener.accept()
        except OSError:
            return
        with lock:
            clients.append(conn)
        threading.Thread(target=serve, args=(conn,), daemon=True).start()


def main():
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(("127.0.0.1", 0))
    listener.listen(8)
    threading.Thread(target=accept, args=(listener,), daemon=True).start()
    say("port %d" % listener.getsockname()[1])
    for line in sys.stdin:
        words = line.split()
        if words[:1] == ["pv"]:
            with lock:
                registers[PROCESS_VALUE] = tenths(float(words[1]))
        elif words[:1] == ["alarm"]:
            with lock:
                registers[int(words[1])] = int(words[2])
        elif words[:1] == ["drop"]:
            with lock:
                for conn in clients:
                    try:
                        conn.shutdown(socket.SHUT_RDWR)
                    except OSError:
                        pass
                clients.clear()
        say("ok")
    listener.close()


if __name__ == "__main__":
    main()
