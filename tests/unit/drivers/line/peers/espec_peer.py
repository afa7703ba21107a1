"""An ESPEC P-300/SCP-220 family controller on its communication port, for the driver tests.

Written from ESPEC's communication function manual (EHS-211M/221M/411M, RS-485, 2007):
commands end in CR LF; setting commands are answered "OK:" and the command, refused ones (and
unanswerable queries) "NA:" and the controller's words (CMD ERR, DATA OUT OF RANGE, PROTECT
ON, ...); MON? answers "temperature,humidity,mode,alarm count"; ROM? the model and ROM
version; and from the P300 command summary as ESPEC North America's library documents it:
TEMP? "air,setpoint,upper limit,lower limit", ALARM? "count[,code...]", TEMP,S<v>,
MODE,CONSTANT|STANDBY|OFF. On RS-485 a command starts with "<address>,", accepted here too.

"alarm CODE" raises alarm CODE (default 1); "refuse" answers setting commands NA:PROTECT ON.
"""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peer_base import Device, report, serve  # noqa: E402

UPPER_C = 150.0
LOWER_C = -70.0


class Espec(Device):
    def default_refusal(self):
        return "PROTECT ON"

    def mode_word(self):
        return "CONSTANT" if self.running else "STANDBY"

    def setting(self, command, action):
        if self.refusal:
            return "NA:" + self.refusal
        result = action()
        return result if result else "OK:" + command

    def handle(self, command):
        m = re.match(r"^\d+,(.*)$", command)  # RS-485 address
        if m:
            command = m.group(1)
        if command == "ROM?":
            return "SU-241 Ver. 1.20"
        if command == "TYPE?":
            return "T,S2,150.0"
        if command == "TEMP?":
            return f"{self.air:.1f},{self.setpoint:.1f},{UPPER_C:.1f},{LOWER_C:.1f}"
        if command == "MON?":
            alarms = 1 if self.alarm else 0
            return f"{self.air:.1f},,{self.mode_word()},{alarms}"
        if command == "MODE?":
            return self.mode_word()
        if command == "ALARM?":
            return f"1,{self.alarm}" if self.alarm else "0"
        m = re.match(r"^TEMP,\s*S([-+]?[0-9.]+)$", command)
        if m:
            value = float(m.group(1))

            def set_it():
                if not LOWER_C <= value <= UPPER_C:
                    return "NA:DATA OUT OF RANGE"
                self.setpoint = value
                report(set=value)
                return None

            return self.setting(command, set_it)
        m = re.match(r"^MODE,(CONSTANT|STANDBY|OFF)$", command)
        if m:
            def mode_it():
                self.running = m.group(1) == "CONSTANT"
                report(running=self.running)
                return None

            return self.setting(command, mode_it)
        return "NA:CMD ERR"


if __name__ == "__main__":
    serve(Espec(), reply_terminator=b"\r\n")
