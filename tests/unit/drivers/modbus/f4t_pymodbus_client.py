"""A pymodbus client playing an F4T master against calstand's Modbus chamber server
(tests/unit/drivers/modbus/pymodbus_cross_test.cpp): the independent implementation that checks
our server's registers, encodings and refusals.

Reads process value, setpoint and mode, writes the setpoint and mode, tries two writes the
controller must refuse, and prints one JSON object with what it saw.
"""
import argparse
import json
import struct

from pymodbus.client import ModbusTcpClient

PROCESS_VALUE = 2820
SETPOINT = 2782
MODE = 2730


def to_words(value, order):
    high, low = struct.unpack(">HH", struct.pack(">f", value))
    return [high, low] if order == "high_first" else [low, high]


def from_words(words, order):
    high, low = words if order == "high_first" else (words[1], words[0])
    return struct.unpack(">f", struct.pack(">HH", high, low))[0]


def exception_code(response):
    return getattr(response, "exception_code", None) if response.isError() else None


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--port", type=int, required=True)
    parser.add_argument("--word-order", choices=["high_first", "low_first"], default="high_first")
    parser.add_argument("--setpoint", type=float, required=True)
    parser.add_argument("--mode", type=int, required=True)
    args = parser.parse_args()
    order = args.word_order

    client = ModbusTcpClient("127.0.0.1", port=args.port)
    if not client.connect():
        print(json.dumps({"error": "cannot connect"}))
        return

    def read_state():
        pv = client.read_holding_registers(PROCESS_VALUE, 2, slave=1)
        sp = client.read_holding_registers(SETPOINT, 2, slave=1)
        mode = client.read_holding_registers(MODE, 1, slave=1)
        return {
            "pv": from_words(pv.registers, order),
            "sp": from_words(sp.registers, order),
            "mode": mode.registers[0],
        }

    out = {"before": read_state()}
    out["setpoint_write_error"] = exception_code(
        client.write_registers(SETPOINT, to_words(args.setpoint, order), slave=1))
    out["mode_write_error"] = exception_code(client.write_register(MODE, args.mode, slave=1))
    out["after"] = read_state()
    out["out_of_range_write_error"] = exception_code(
        client.write_registers(SETPOINT, to_words(5000.0, order), slave=1))
    out["process_value_write_error"] = exception_code(
        client.write_registers(PROCESS_VALUE, to_words(20.0, order), slave=1))
    out["unmapped_read_error"] = exception_code(client.read_holding_registers(100, 1, slave=1))
    client.close()
    print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
