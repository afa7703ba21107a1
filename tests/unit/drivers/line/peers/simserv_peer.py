"""A Weiss/Voetsch chamber's S!MPAC simserv server, for the driver tests.

Written from the simserv protocol as users' public code documents it (IzaakWN's
ClimateChamberMonitor, SengerM's VotschTechnik-climate-chamber-Python, citing S!MPAC simserv
2019.05 sections 2.2, 3.2, 5): a command is its number, the chamber index and its arguments,
separated by the byte 0xB6, ended by CR; the reply starts with the return code (1 accepted,
-5 unknown command, -6 too few or wrong parameters, -8 data could not be read), then the data,
separated by 0xB6, ended by CR LF. 99997 chamber information, 11001/11002 set/get the nominal
value, 11004 the actual value, 11068/11072 gradients up/down, 10012 status (1 not running,
3 running, +4 warnings, +8 alarms), 14001 manual mode on/off, 14003 digital output value
(output 1: the manual mode, "get running" in the users' code).

"alarm" sets the status' alarm bit; "refuse [CODE]" answers settings with CODE (default -6).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peer_base import Device, report, serve  # noqa: E402

SEP = "\u00b6"


class SimServ(Device):
    def default_refusal(self):
        return "-6"

    def ok(self, *data):
        return SEP.join(["1"] + [str(d) for d in data])

    def handle(self, command):
        parts = command.split(SEP)
        number, args = parts[0], parts[2:]  # parts[1]: the chamber index, always 1
        if number == "99997":
            return self.ok({"1": "VT 4002", "2": "19", "3": "58566041870010"}.get(args[0], ""))
        if number == "11004":
            return self.ok(f"{self.air:.1f}")
        if number == "11002":
            return self.ok(f"{self.setpoint:.1f}")
        if number == "14003":  # digital output value; output 1 is the manual mode's on/off
            return self.ok(1 if self.running else 0)
        if number == "10012":
            return self.ok((3 if self.running else 1) + (8 if self.alarm else 0))
        if number in ("11001", "11068", "11072", "14001"):
            if self.refusal:
                return self.refusal
            if len(args) != 2:
                return "-6"
            try:
                value = float(args[1])
            except ValueError:
                return "-6"
            if number == "11001":
                self.setpoint = value
                report(set=value)
            elif number == "11068":
                report(gradient_up=value)
            elif number == "11072":
                report(gradient_down=value)
            else:
                self.running = value == 1
                report(running=self.running)
            return self.ok()
        return "-5"


if __name__ == "__main__":
    serve(SimServ(), reply_terminator=b"\r\n", separators=b"\r")
