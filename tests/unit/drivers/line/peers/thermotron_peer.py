"""A Thermotron 8800 programmer on its Ethernet interface, for the driver tests.

Written from Thermotron's 8800 interface command descriptions (operation commands answered
"0"; ALRMn? a coded integer: bit 0 low deviation, 1 high deviation, 4 low process, 5 high
process alarm) and the 8200/3800 command entries users' public code quotes (IDEN?, PVAR1?,
SETP1?, SETP1,<v>, RUNM, STOP; commands end in CR). The documents found give no refusal
reply: this peer answers a refused command "ERR" and its words, the reading calstand's
docs/protocols.md records as assumed.

"alarm BITS" sets ALRM1?'s bits (e.g. 32, high process); "refuse [WORDS]" refuses
operations.
"""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peer_base import Device, report, serve  # noqa: E402


class Thermotron(Device):
    def default_refusal(self):
        return "SETPOINT LOCKED"

    def handle(self, command):
        command = command.strip()
        if command == "IDEN?":
            return "THERMOTRON 8800 V3.2"
        if command == "PVAR1?":
            return f"{self.air:.3f}"
        if command == "SETP1?":
            return f"{self.setpoint:.3f}"
        if command == "ALRM1?":
            return str(int(self.alarm) if self.alarm and self.alarm.isdigit() else
                       (32 if self.alarm else 0))
        m = re.match(r"^SETP1,([-+]?[0-9.]+)$", command)
        if m:
            if self.refusal:
                return "ERR " + self.refusal
            self.setpoint = float(m.group(1))
            report(set=self.setpoint)
            return "0"
        if command in ("RUNM", "STOP"):
            if self.refusal:
                return "ERR " + self.refusal
            self.running = command == "RUNM"
            report(running=self.running)
            return "0"
        return "ERR UNKNOWN COMMAND"


if __name__ == "__main__":
    serve(Thermotron(), reply_terminator=b"\r\n", separators=b"\r\n")
