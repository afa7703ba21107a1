#!/usr/bin/python3
"""An independent Xsens MTi device peer on a pseudo-terminal, written from the Xsens "MT
Low-Level Communication Protocol Documentation" (MT0101P): Xbus messages (preamble 0xFA, BID
0xFF, MID, LEN or 0xFF + 2-byte extended length, data, checksum making every byte after the
preamble sum to 0 mod 256) and MTData2 packets (XDI u16, size u8, big-endian data).

Prints the slave path as its first stdout line, sends WakeUp and a few packets of its stored
configuration (it powers up measuring), answers GoToConfig, ReqDID, ReqProductCode, ReqFWRev,
SetOutputConfiguration and GoToMeasurement, then streams COUNT packets of a known signal at the
configured rate in the configured precision and coordinate system:

  packet k: PacketCounter k, SampleTimeFine 50000 + k * 10000 / rate,
            gyro = (sin(k/10), cos(k/10), 0.5 + k/100) deg/s (sent in rad/s),
            accel = (0.01 k, -0.5, 9.81) m/s^2, temperature 25 + 0.01 k degC when due.

Packet BAD is sent with a broken checksum, and 7 bytes of garbage and an Error 0x29 message go
before packet BAD + 5. Standard library only. Usage: xsens_peer.py [COUNT] [BAD]
"""
import math
import os
import select
import struct
import sys
import time
import tty

COUNT = int(sys.argv[1]) if len(sys.argv) > 1 else 60
BAD = int(sys.argv[2]) if len(sys.argv) > 2 else 20

PREAMBLE, BID = 0xFA, 0xFF


def message(mid, data=b""):
    if len(data) < 0xFF:
        body = bytes([BID, mid, len(data)]) + data
    else:
        body = bytes([BID, mid, 0xFF]) + struct.pack(">H", len(data)) + data
    return bytes([PREAMBLE]) + body + bytes([(-sum(body)) & 0xFF])


def value(v, precision):
    if precision == 0:
        return struct.pack(">f", v)
    if precision == 1:  # fixed point 12.20
        return struct.pack(">i", int(round(v * (1 << 20))))
    if precision == 2:  # fixed point 16.32: 32 fractional bits, then the 16-bit integer part
        raw = int(round(v * (1 << 32))) & ((1 << 48) - 1)
        return struct.pack(">IH", raw & 0xFFFFFFFF, raw >> 32)
    return struct.pack(">d", v)


def item(xdi, values):
    precision = xdi & 0x3
    data = b"".join(value(v, precision) for v in values)
    return struct.pack(">HB", xdi, len(data)) + data


def axes(xdi, v):
    # NED (bits 3..2 = 01) turns the sensor frame 180 degrees about x.
    if (xdi & 0xC) == 0x4:
        return (v[0], -v[1], -v[2])
    return v


class Unit:
    def __init__(self):
        self.config = [(0x1020, 0xFFFF), (0x1060, 0xFFFF), (0x4020, 100), (0x8020, 100),
                       (0x0810, 100)]
        self.measuring = True
        self.started = None

    def rate(self, kind):
        for xdi, hz in self.config:
            if xdi & 0xFFF0 == kind:
                return hz
        return 0

    def packet(self, k):
        rate = self.rate(0x8020)
        d = b""
        for xdi, hz in self.config:
            kind = xdi & 0xFFF0
            if kind == 0x1020:
                d += struct.pack(">HBH", 0x1020, 2, k & 0xFFFF)
            elif kind == 0x1060:
                d += struct.pack(">HBI", 0x1060, 4, (50000 + k * 10000 // rate) & 0xFFFFFFFF)
            elif kind == 0x4020:
                d += item(xdi, axes(xdi, (0.01 * k, -0.5, 9.81)))
            elif kind == 0x8020:
                g = (math.sin(k / 10), math.cos(k / 10), 0.5 + k / 100)
                d += item(xdi, axes(xdi, tuple(math.radians(x) for x in g)))
            elif kind == 0x0810 and k % max(1, rate // hz) == 0:
                d += item(xdi, (25 + 0.01 * k,))
        return message(0x36, d)

    def answer(self, mid, data):
        if mid == 0x30:
            self.measuring = False
            return message(0x31)
        if mid == 0x10:
            self.measuring = True
            self.started = time.monotonic() + 0.5  # give the host time to start its reader
            return message(0x11)
        if mid == 0x00:
            return message(0x01, struct.pack(">I", 0x037001A5))
        if mid == 0x1C:
            return message(0x1D, b"MTi-670-2A8G4")
        if mid == 0x12:
            return message(0x13, bytes([1, 8, 2]) + struct.pack(">II", 55, 12345))
        if mid == 0xC0:
            if len(data) % 4 or self.measuring:
                return message(0x42, bytes([0x21 if len(data) % 4 else 0x04]))
            config = [struct.unpack(">HH", data[i:i + 4]) for i in range(0, len(data), 4)]
            rate = [hz for xdi, hz in config if xdi & 0xFFF0 == 0x8020]
            if not rate or 2000 % rate[0]:
                return message(0x42, bytes([0x21]))
            self.config = config
            return message(0xC1, data)
        return message(0x42, bytes([0x04]))


def messages(buf):
    """Complete valid messages in buf, and the bytes left over."""
    out = []
    while True:
        start = buf.find(bytes([PREAMBLE]))
        if start < 0:
            return out, b""
        buf = buf[start:]
        if len(buf) < 4:
            return out, buf
        if buf[1] != BID:
            buf = buf[1:]
            continue
        length, header = buf[3], 4
        if length == 0xFF:
            if len(buf) < 6:
                return out, buf
            length, header = struct.unpack(">H", buf[4:6])[0], 6
        size = header + length + 1
        if len(buf) < size:
            return out, buf
        if sum(buf[1:size]) & 0xFF:
            buf = buf[1:]
            continue
        out.append((buf[2], buf[header:header + length]))
        buf = buf[size:]


def main():
    master, slave = os.openpty()
    tty.setraw(master)
    tty.setraw(slave)
    print(os.ttyname(slave), flush=True)
    unit = Unit()
    out = message(0x3E)  # WakeUp at power-on; unanswered, the unit measures
    for k in range(5):
        out += unit.packet(1000 + k)
    os.write(master, out)
    pending = b""
    k = 0
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline and k < COUNT:
        readable, _, _ = select.select([master], [], [], 0.002)
        if readable:
            pending += os.read(master, 4096)
            found, pending = messages(pending)
            for mid, data in found:
                os.write(master, unit.answer(mid, data))
        if unit.measuring and unit.started is not None and time.monotonic() >= unit.started:
            frame = unit.packet(k)
            if k == BAD:
                frame = frame[:-1] + bytes([(frame[-1] + 1) & 0xFF])
            if k == BAD + 5:
                frame = bytes([0x00, 0x13, 0x37, 0xFA, 0x00, 0xAA, 0x55]) + \
                    message(0x42, bytes([0x29])) + frame
            os.write(master, frame)
            k += 1
            unit.started += 1.0 / unit.rate(0x8020)
    # Stay until the test is done with the line.
    sys.stdin.read()


if __name__ == "__main__":
    main()
