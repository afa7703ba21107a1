#!/usr/bin/python3
"""Independent peer for calstand's DBC support: encodes signal values into CAN frames the way
the DBC convention says, and prints them as candump log lines "(t) can0 ID#DATA".

Written from the DBC format's description (Vector CANdb++: `SG_ name [M|mN] : start|length@order
sign (factor,offset) [min|max] "unit" receivers`), not from calstand's C++:
  - Intel (@1): the start bit is the least significant bit; bit k of the value goes to
    message bit start + k, where message bit n is bit n % 8 of byte n // 8.
  - Motorola (@0): the start bit is the most significant bit, in the same "sawtooth" numbering
    (bit n is bit n % 8 of byte n // 8); moving to less significant bits goes down within a
    byte (bit 7 -> 0) and then to bit 7 of the next byte.
  - raw = round((physical - offset) / factor), two's complement for '-' signals; for a
    multiplexed signal (mN) the message's switch (M) is set to N.

Usage: dbc_peer.py REQUEST.json   (or "-" for stdin)
REQUEST: {"dbc": "path", "frames": [{"message": "NAME", "values": {"SIGNAL": 1.5, ...},
          "t": 0.01}, ...]}
Every frame is 8 bytes unless "dlc" is given; unnamed bits are 0. Standard library only.
"""

import json
import re
import sys

SG_RE = re.compile(
    r'^\s*SG_\s+(\w+)\s*(M|m\d+)?\s*:\s*(\d+)\|(\d+)@([01])([+-])\s*'
    r'\(\s*([^,]+)\s*,\s*([^)]+)\)')
BO_RE = re.compile(r'^\s*BO_\s+(\d+)\s+(\w+)\s*:\s*(\d+)')


def read_dbc(path):
    messages = {}
    current = None
    with open(path, encoding='latin-1') as f:
        for line in f:
            m = BO_RE.match(line)
            if m:
                current = {'id': int(m.group(1)), 'dlc': int(m.group(3)), 'signals': {}}
                messages[m.group(2)] = current
                continue
            s = SG_RE.match(line)
            if s and current is not None:
                current['signals'][s.group(1)] = {
                    'mux': s.group(2), 'start': int(s.group(3)), 'length': int(s.group(4)),
                    'intel': s.group(5) == '1', 'signed': s.group(6) == '-',
                    'factor': float(s.group(7)), 'offset': float(s.group(8))}
            elif line.strip() and not line.startswith((' ', '\t')):
                current = None
    return messages


def put_bits(data, sig, raw):
    """Writes the `length` low bits of raw into data (a bytearray) per the DBC convention."""
    n = sig['length']
    raw &= (1 << n) - 1
    if sig['intel']:
        for k in range(n):
            pos = sig['start'] + k
            set_bit(data, pos // 8, pos % 8, (raw >> k) & 1)
    else:
        byte, bit = sig['start'] // 8, sig['start'] % 8
        for k in range(n - 1, -1, -1):  # most significant first
            set_bit(data, byte, bit, (raw >> k) & 1)
            if bit == 0:
                byte, bit = byte + 1, 7
            else:
                bit -= 1


def set_bit(data, byte, bit, value):
    if value:
        data[byte] |= 1 << bit
    else:
        data[byte] &= ~(1 << bit) & 0xFF


def raw_value(sig, physical):
    raw = int(round((physical - sig['offset']) / sig['factor']))
    lo, hi = (-(1 << (sig['length'] - 1)), (1 << (sig['length'] - 1)) - 1) if sig['signed'] \
        else (0, (1 << sig['length']) - 1)
    return max(lo, min(hi, raw))


def main():
    source = sys.stdin if sys.argv[1] == '-' else open(sys.argv[1])
    request = json.load(source)
    messages = read_dbc(request['dbc'])
    for i, frame in enumerate(request['frames']):
        msg = messages[frame['message']]
        data = bytearray(frame.get('dlc', 8))
        for name, physical in frame['values'].items():
            sig = msg['signals'][name]
            if sig['mux'] and sig['mux'] != 'M':
                switch = next(s for s in msg['signals'].values() if s['mux'] == 'M')
                put_bits(data, switch, int(sig['mux'][1:]))
            put_bits(data, sig, raw_value(sig, physical))
        can_id = msg['id']
        if can_id & 0x80000000:
            text_id = '%08X' % (can_id & 0x1FFFFFFF)
        else:
            text_id = '%03X' % can_id
        t = frame.get('t', 0.001 * i)
        print('(%.6f) can0 %s#%s' % (t, text_id, data.hex().upper()))
    sys.stdout.flush()


if __name__ == '__main__':
    main()
