#!/usr/bin/python3
"""An independent VN-100 on a pseudo-terminal, written from the VectorNav VN-100 User Manual
(UM001 v2.22): ASCII register commands ($VNRRG/$VNWRG, 8-bit XOR checksum, *XX bypass,
$VNERR codes) and the binary output message (sync 0xFA, group byte, one u16 field mask per
group, little-endian payload, CRC-16-CCITT with initial value 0, sent most significant byte
first). Standard library only.

Prints the slave path as its first line, answers the configuration dialogue, prints each
register write it accepted as a JSON line, then, once "stream" arrives on stdin, streams
COUNT messages of a known signal at the configured rate, with one message left out, one with
a broken CRC, a run of garbage and a $VNERR,12 among them, and prints {"sent": ...}.
"""
import json
import math
import os
import select
import struct
import sys
import tty

COUNT = 60
DROPPED = 20       # never sent: a sequence gap
CORRUPTED = 30     # sent with a bit flipped: a CRC error (and its bytes garbage)
GARBAGE_BEFORE = 40
GARBAGE = bytes([0x00, 0x11, 0x22, 0x33, 0x44])
ERROR_AFTER = 45
IMU_RATE_HZ = 800.0
START_NS = 1_000_000_000  # TimeStartup of the first message [ns]

MODEL, HARDWARE, SERIAL, FIRMWARE = "VN-100T-CR", "5", "0100099999", "2.1.0.0"


def checksum(body):
    c = 0
    for ch in body.encode("ascii"):
        c ^= ch
    return c


def line(body):
    return ("$%s*%02X\r\n" % (body, checksum(body))).encode("ascii")


def crc16_ccitt(data):
    crc = 0
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else (crc << 1)
            crc &= 0xFFFF
    return crc


def signal(k):
    """Sample k: gyro [deg/s], accel [m/s^2], temperature [degC]."""
    gyro = (10.0 * math.sin(k / 10.0), 5.0 * math.cos(k / 10.0), 0.1 * k)
    accel = (0.01 * k, -9.80665, math.cos(k / 7.0))
    return gyro, accel, 25.0 + 0.01 * k


# Field sizes of the fields this peer can send (UM001 binary output field tables).
COMMON_FIELDS = {0: "TimeStartup"}
IMU_FIELDS = {2: "UncompAccel", 3: "UncompGyro", 4: "Temp", 9: "Accel", 10: "AngularRate"}


def message(k, period_ns, groups, common, imu):
    gyro, accel, temp = signal(k)
    gyro_rad = tuple(g * math.pi / 180.0 for g in gyro)
    header = bytes([groups])
    payload = b""
    if groups & 0x01:
        header += struct.pack("<H", common)
        if common & 0x0001:
            payload += struct.pack("<Q", START_NS + k * period_ns)
    if groups & 0x04:
        header += struct.pack("<H", imu)
        for bit in sorted(IMU_FIELDS):
            if not imu & (1 << bit):
                continue
            name = IMU_FIELDS[bit]
            if name in ("UncompAccel", "Accel"):
                payload += struct.pack("<3f", *accel)
            elif name in ("UncompGyro", "AngularRate"):
                payload += struct.pack("<3f", *gyro_rad)
            else:
                payload += struct.pack("<f", temp)
    body = header + payload
    return b"\xfa" + body + struct.pack(">H", crc16_ccitt(body))


class Unit:
    def __init__(self):
        self.ador = 14  # factory default: an ASCII async output is on
        self.binary = None  # (mode, divisor, groups, common, imu)

    def answer(self, text):
        """The reply to one received line (without its end of line)."""
        if not text.startswith("$") or "*" not in text:
            return b""
        body, _, given = text[1:].rpartition("*")
        if given != "XX" and given.upper() != "%02X" % checksum(body):
            return line("VNERR,03")
        f = body.split(",")
        if f[0] not in ("VNRRG", "VNWRG"):
            return line("VNERR,04")
        if len(f) < 2 or not f[1].isdigit():
            return line("VNERR,05")
        reg = int(f[1])
        if f[0] == "VNRRG":
            values = {1: MODEL, 2: HARDWARE, 3: SERIAL, 4: FIRMWARE, 6: str(self.ador)}
            if reg not in values:
                return line("VNERR,08")
            return line("%s,%s,%s" % (f[0], f[1], values[reg]))
        if reg == 6:
            self.ador = int(f[2])
        elif reg == 75:
            mode, divisor, groups = int(f[2]), int(f[3]), int(f[4], 16)
            words = [int(w, 16) for w in f[5:]]
            if divisor < 1 or groups & ~0x05 or len(words) != bin(groups).count("1"):
                return line("VNERR,07")
            common = words.pop(0) if groups & 0x01 else 0
            imu = words.pop(0) if groups & 0x04 else 0
            self.binary = (mode, divisor, groups, common, imu)
        else:
            return line("VNERR,08")
        print(json.dumps({"write": reg, "values": f[2:]}), flush=True)
        return line(body)  # a write is answered with the command echoed


def main():
    master, slave = os.openpty()
    tty.setraw(slave)
    tty.setraw(master)
    print(os.ttyname(slave), flush=True)
    unit = Unit()
    pending = b""
    streaming = False
    while True:
        ready, _, _ = select.select([master, sys.stdin], [], [], 0.05)
        if sys.stdin in ready:
            request = sys.stdin.readline()
            if not request:
                return
            streaming = request.strip() == "stream"
        if master in ready:
            pending += os.read(master, 4096)
            while b"\n" in pending:
                raw, pending = pending.split(b"\n", 1)
                reply = unit.answer(raw.decode("ascii", "replace").rstrip("\r"))
                if reply:
                    os.write(master, reply)
        if streaming:
            streaming = False
            mode, divisor, groups, common, imu = unit.binary
            period_ns = int(round(divisor * 1e9 / IMU_RATE_HZ))
            sent = 0
            for k in range(COUNT):
                if k == GARBAGE_BEFORE:
                    os.write(master, GARBAGE)
                if k == DROPPED:
                    continue
                m = bytearray(message(k, period_ns, groups, common, imu))
                if k == CORRUPTED:
                    m[12] ^= 0x01
                os.write(master, bytes(m))
                sent += 1
                if k == ERROR_AFTER:
                    os.write(master, line("VNERR,12"))
            print(json.dumps({"sent": sent}), flush=True)


if __name__ == "__main__":
    main()
