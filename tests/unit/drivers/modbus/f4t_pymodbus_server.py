"""A Watlow F4T stand-in built on pymodbus: the independent implementation calstand's Modbus
driver is cross-tested against (tests/unit/drivers/modbus/pymodbus_cross_test.cpp).

Holds the F4T loop-1 holding registers (process value 2820 and setpoint 2782 as float32 in two
registers, control mode 2730: 10 = auto, 62 = off) on 127.0.0.1 at an ephemeral port.

Output (stdout, one line each, flushed):
  port <N>                       once listening
  {"write": a, "values": [...], "setpoint_c": x, "mode": m}
                                 after every client write, with the registers as decoded here
Input (stdin): "pv <degC>" sets the process value ("pv nan" for a sensor fault); end of input
stops the server.
"""
import argparse
import asyncio
import json
import struct
import sys

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.server.async_io import ModbusTcpServer

PROCESS_VALUE = 2820
SETPOINT = 2782
MODE = 2730
MODE_OFF = 62


def to_words(value, order):
    high, low = struct.unpack(">HH", struct.pack(">f", value))
    return [high, low] if order == "high_first" else [low, high]


def from_words(words, order):
    high, low = words if order == "high_first" else (words[1], words[0])
    return struct.unpack(">f", struct.pack(">HH", high, low))[0]


class EchoBlock(ModbusSequentialDataBlock):
    """Holding registers that report every client write on stdout."""

    def __init__(self, order):
        super().__init__(0, [0] * 3000)
        self.order = order
        self.echo = False

    def setValues(self, address, values):  # pylint: disable=invalid-name
        super().setValues(address, values)
        if self.echo:
            print(json.dumps({
                "write": address,
                "values": list(values),
                "setpoint_c": from_words(self.getValues(SETPOINT, 2), self.order),
                "mode": self.getValues(MODE, 1)[0],
            }), flush=True)

    def set_quietly(self, address, values):
        self.echo = False
        self.setValues(address, values)
        self.echo = True


async def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--word-order", choices=["high_first", "low_first"], default="high_first")
    parser.add_argument("--pv", type=float, default=23.5)
    args = parser.parse_args()

    block = EchoBlock(args.word_order)
    block.set_quietly(PROCESS_VALUE, to_words(args.pv, args.word_order))
    block.set_quietly(SETPOINT, to_words(args.pv, args.word_order))
    block.set_quietly(MODE, [MODE_OFF])
    # zero_mode: the address on the wire is the index in the block (pymodbus adds 1 otherwise).
    context = ModbusServerContext(slaves=ModbusSlaveContext(hr=block, zero_mode=True), single=True)
    server = ModbusTcpServer(context, address=("127.0.0.1", 0), allow_reuse_address=True)
    task = asyncio.create_task(server.serve_forever())
    await server.serving
    print(f"port {server.server.sockets[0].getsockname()[1]}", flush=True)

    loop = asyncio.get_running_loop()
    while True:
        line = await loop.run_in_executor(None, sys.stdin.readline)
        if not line:
            break
        words = line.split()
        if len(words) == 2 and words[0] == "pv":
            block.set_quietly(PROCESS_VALUE, to_words(float(words[1]), args.word_order))
            print("ok", flush=True)
    await server.shutdown()
    task.cancel()


if __name__ == "__main__":
    asyncio.run(main())
