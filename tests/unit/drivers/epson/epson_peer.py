#!/usr/bin/python3
"""An Epson M-G366PDG0 on a pseudo-terminal, written from the data sheets' UART protocol
(M-G362PDC1 Data Sheet Rev.20131217 Tables 6.10, 6.11, 6.14; M-G365PD Data Sheet Rev.20190905
register map), independently of the C++ code. Standard library only.

Prints the slave path as its first line, answers register reads in configuration mode, takes
register writes, and in UART auto mode after "go to sampling" streams burst frames of the
deterministic signal below (frame index k of the output rate):

    gyro    = (10 sin(k/10), -2.5, 0.01 k) deg/s
    accel   = (0.5 cos(k/10), 0, 9.80665) m/s^2
    temperature = 30 + 0.01 k degC
    COUNT   = (64336 + k * 2000/rate) mod 65536   (counts at the 2000 Sps base rate; wraps at
              k = 60 at 100 Hz)

With --faults it also sends, once, a copy of frame 50 with a wrong checksum before the real
one, and five bytes of garbage after frame 70.
"""
import math
import os
import select
import struct
import sys
import time
import tty

GYRO_SF = 1.0 / 66  # deg/s per LSB (16-bit); /65536 for 32-bit
ACCL_SF = 0.25  # mG per LSB (16-bit)
TEMP_SF = 0.00390625  # degC per LSB around 25 degC
RATES = {0x00: 2000.0, 0x01: 1000.0, 0x02: 500.0, 0x03: 250.0, 0x04: 125.0, 0x05: 62.5,
         0x06: 31.25, 0x07: 15.625, 0x08: 400.0, 0x09: 200.0, 0x0A: 100.0, 0x0B: 80.0,
         0x0C: 50.0, 0x0D: 40.0, 0x0E: 25.0, 0x0F: 20.0}


def ascii_registers(text):
    text = text.ljust(8)[:8].encode()
    return [text[i] | (text[i + 1] << 8) for i in range(0, 8, 2)]


class Device:
    def __init__(self):
        self.window = 0
        self.sampling = False
        self.regs = {(0, 0x04): 0x0000,  # DIAG_STAT
                     (1, 0x04): 0x0100, (1, 0x06): 0x0004, (1, 0x08): 0x0000,
                     (1, 0x0C): 0xF006, (1, 0x0E): 0x0000, (1, 0x72): 0x0209}
        for i, v in enumerate(ascii_registers("G366PDG0")):
            self.regs[(1, 0x6A + 2 * i)] = v
        for i, v in enumerate(ascii_registers("PEER0042")):
            self.regs[(1, 0x74 + 2 * i)] = v

    def command(self, a, d):
        """One 3-byte command; returns the reply bytes."""
        if a & 0x80 == 0:  # read: A, don't care, CR -> A, hi, lo, CR
            if self.sampling:
                return b""
            if a == 0x7E:
                value = self.window
            elif self.window == 0 and a == 0x02:
                value = 0x0400  # MODE_STAT: configuration mode
            else:
                value = self.regs.get((self.window, a), 0)
            return bytes([a, value >> 8, value & 0xFF, 0x0D])
        a &= 0x7F
        if a == 0x7E:
            self.window = d & 1
        elif self.window == 0 and a == 0x03:
            if d == 0x01:
                self.sampling = True
            elif d == 0x02:
                self.sampling = False
        elif not self.sampling:
            key = (self.window, a & 0xFE)
            old = self.regs.get(key, 0)
            self.regs[key] = (old & 0x00FF) | (d << 8) if a & 1 else (old & 0xFF00) | d
        return b""

    def auto(self):
        return self.regs[(1, 0x08)] & 1 == 1

    def rate(self):
        return RATES[(self.regs[(1, 0x04)] >> 8) & 0x0F]

    def wide(self):
        return self.regs[(1, 0x0E)] & 0x7000 == 0x7000


def frame(k, rate, wide, bad_checksum=False):
    gyro = (10 * math.sin(k / 10), -2.5, 0.01 * k)
    accel = (0.5 * math.cos(k / 10), 0.0, 9.80665)
    temp = 30 + 0.01 * k
    scale = 65536 if wide else 1
    raw = [round((temp - 25) / TEMP_SF * scale)]
    raw += [round(g / GYRO_SF * scale) for g in gyro]
    raw += [round(a / 9.80665 * 1000 / ACCL_SF * scale) for a in accel]
    count = (64336 + k * round(2000 / rate)) % 65536
    body = struct.pack(">H", 0xFE00)  # ND flags for temperature, gyro, accel; EA clear
    body += b"".join(struct.pack(">i" if wide else ">h", v) for v in raw)
    body += struct.pack(">H", count)
    checksum = sum(struct.unpack(">%dH" % (len(body) // 2), body)) & 0xFFFF
    if bad_checksum:
        checksum ^= 0x0101
    return b"\x80" + body + struct.pack(">H", checksum) + b"\x0d"


def main():
    faults = "--faults" in sys.argv
    master, slave = os.openpty()
    tty.setraw(slave)
    print(os.ttyname(slave), flush=True)
    dev = Device()
    pending = b""
    k = 0
    next_time = None
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        streaming = dev.sampling and dev.auto()
        timeout = 0.05
        if streaming:
            if next_time is None:
                next_time = time.monotonic()
            timeout = max(0.0, next_time - time.monotonic())
        else:
            next_time = None
        ready, _, _ = select.select([master], [], [], timeout)
        if ready:
            try:
                pending += os.read(master, 4096)
            except OSError:
                return
            while len(pending) >= 3:
                if pending[2] != 0x0D:
                    pending = pending[1:]
                    continue
                reply = dev.command(pending[0], pending[1])
                pending = pending[3:]
                if reply:
                    os.write(master, reply)
            continue
        if streaming and time.monotonic() >= next_time:
            out = b""
            if faults and k == 50:
                out += frame(k, dev.rate(), dev.wide(), bad_checksum=True)
            out += frame(k, dev.rate(), dev.wide())
            if faults and k == 70:
                out += b"\x11\x22\x33\x44\x55"
            os.write(master, out)
            k += 1
            next_time += 1.0 / dev.rate()


if __name__ == "__main__":
    main()
