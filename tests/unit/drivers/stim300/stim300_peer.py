#!/usr/bin/python3
"""An independent STIM300 on a pseudo-terminal, written from the STIM300 datasheet (Sensonor
TS1524) as docs/protocols.md ("Sensonor STIM300") reads it, not from the C++ driver.

Prints the slave path as its first line, then behaves as a unit in normal mode: streams
datagram 0xA7 (rate, acceleration, inclination, temperatures) with CR LF at the given rate,
and answers the normal-mode commands N, I and C (ended by CR) with the part number (0xB3),
serial number (0xB7) and configuration (0xBD) datagrams, the identifiers with CR LF. The signal is a function of the 8-bit counter c:
  gyro  [deg/s] = (sin(2 pi 3 c / 256), cos(2 pi 3 c / 256), 0.5)
  acc   [g]     = (0.1 sin(2 pi c / 256), -0.2, 1.0)       (10 g unit: 2^19 counts per g)
  incl  [g]     = (0, 0, 1)
  temperatures  = 30 + 0.25 (c mod 4) degC
latency 400 us. One second after the configuration reply it sends one datagram with a broken
CRC, three garbage bytes, and a datagram flagging "gyro x: outside operating conditions".
Standard library only. Usage: stim300_peer.py RATE_HZ
"""
import math
import os
import select
import sys
import time
import tty

RATE_HZ = float(sys.argv[1]) if len(sys.argv) > 1 else 500.0
PART_DIGITS = "841672500301"  # part number 84167-2500-301, one 4-bit code per digit
SERIAL_DIGITS = "25581234"  # serial number, BCD
CRLF = b"\r\n"


def crc32_stim(data):
    """Polynomial 0x04C11DB7, init 0xFFFFFFFF, MSB first, no final XOR."""
    crc = 0xFFFFFFFF
    for byte in data:
        crc ^= byte << 24
        for _ in range(8):
            if crc & 0x80000000:
                crc = ((crc << 1) ^ 0x04C11DB7) & 0xFFFFFFFF
            else:
                crc = (crc << 1) & 0xFFFFFFFF
    return crc


def with_crc(body):
    """Body + CRC over the body padded with 0x00 dummy bytes to a multiple of 4, + CR LF."""
    padded = body + b"\x00" * ((4 - len(body) % 4) % 4)
    return body + crc32_stim(padded).to_bytes(4, "big") + CRLF


def s24(value):
    return (int(round(value)) & 0xFFFFFF).to_bytes(3, "big")


def s16(value):
    return (int(round(value)) & 0xFFFF).to_bytes(2, "big")


def datagram(c, gyro_status=0):
    phase = 2 * math.pi * c / 256
    gyro = (math.sin(3 * phase), math.cos(3 * phase), 0.5)
    acc = (0.1 * math.sin(phase), -0.2, 1.0)
    incl = (0.0, 0.0, 1.0)
    temp = 30 + 0.25 * (c % 4)
    body = bytes([0xA7])
    body += b"".join(s24(g * 2 ** 14) for g in gyro) + bytes([gyro_status])
    body += b"".join(s24(a * 2 ** 19) for a in acc) + bytes([0])
    body += b"".join(s24(a * 2 ** 22) for a in incl) + bytes([0])
    for _ in range(3):  # gyro, accelerometer, inclinometer temperatures and their status
        body += s16(temp * 256) * 3 + bytes([0])
    body += bytes([c & 0xFF]) + (400).to_bytes(2, "big")
    return with_crc(body)


def digits_datagram(identifier, digits):
    """Two 4-bit codes a byte, first digit in the high nibble."""
    return with_crc(bytes([identifier]) + bytes.fromhex(digits))


def configuration():
    # 16 configuration bytes; calstand does not interpret them, so they stay zero here.
    return with_crc(bytes([0xBD]) + bytes(16))


def main():
    master, slave = os.openpty()
    tty.setraw(master)
    tty.setraw(slave)
    print(os.ttyname(slave), flush=True)
    os.set_blocking(master, False)
    out = bytearray()
    line = b""
    k = 0
    faults_at = None
    start = time.monotonic()
    while True:
        # Commands from the host.
        readable, _, _ = select.select([master], [], [], 0.002)
        if readable:
            try:
                data = os.read(master, 256)
            except OSError:
                data = b""
            for b in data:
                if b == 0x0D:
                    if line == b"N":  # part number datagram, with CR LF: 0xB3
                        out += digits_datagram(0xB3, PART_DIGITS)
                    elif line == b"I":  # serial number datagram, with CR LF: 0xB7
                        out += digits_datagram(0xB7, SERIAL_DIGITS)
                    elif line == b"C":
                        out += configuration()
                        if faults_at is None:
                            faults_at = k + int(RATE_HZ)
                    line = b""
                elif b != 0x0A:
                    line = (line + bytes([b]))[-16:]
        # Datagrams due by now, at the sample rate (dropped while nobody drains the line).
        due = int((time.monotonic() - start) * RATE_HZ)
        while k < due:
            c = k & 0xFF
            if faults_at is not None and k == faults_at:
                bad = bytearray(datagram(c))
                bad[5] ^= 0x01  # a broken CRC
                piece = bytes(bad)
            elif faults_at is not None and k == faults_at + 1:
                piece = b"\x00\x11\x22" + datagram(c)
            elif faults_at is not None and k == faults_at + 2:
                piece = datagram(c, gyro_status=0x21)
            else:
                piece = datagram(c)
            if len(out) < 4096:
                out += piece
            k += 1
        if out:
            try:
                n = os.write(master, bytes(out))
                del out[:n]
            except BlockingIOError:
                pass
            except OSError:
                return


if __name__ == "__main__":
    main()
