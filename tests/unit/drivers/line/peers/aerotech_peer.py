"""An Aerotech A3200 (or Ensemble) ASCII command interface as users' public code shows it
(github.com/epics-modules/motor motorApp/AerotechSrc/drvA3200Asyn.cc and drvEnsembleAsyn; a
scanner client in Python), for LineTable's tests: TCP (the controller's port 8000; here a free
port), commands ended by the EOS character LF.

What it speaks, from that code:
- every command is answered by one line starting with '%' (success; a query's value follows),
  '!' (the command is invalid) or '#' (acknowledged but cannot execute: a fault);
- ENABLE/DISABLE <axis>, FAULTACK <axis>, ABORT <axis>, 'MOVEABS <axis> <pos> <axis>F <speed>',
  'FREERUN <axis> <speed>', 'RAMP MODE <axis> RATE', 'RAMP RATE <axis> <accel>',
  'WAIT MODE NOWAIT';
- queries PFBKPROG(<axis>), VFBK(<axis>), AXISFAULT(<axis>) and AXISSTATUS(<axis>) with bit 0
  enabled, bit 2 in position, bit 3 move active.
Axes are X and Y. There is no sine command.
"""

import os
import re
import sys

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import table_peer  # noqa: E402

table = table_peer.Table(["X", "Y"])
for _a in table.axes.values():
    _a.servo = False  # DISABLEd until ENABLE
    _a.mode = "off"
FAULT_CODES = {}  # axis name -> AXISFAULT word


class Invalid(Exception):
    pass


class Fault(Exception):
    pass


def axis_of(name):
    a = table.axes.get(name.strip().upper())
    if a is None:
        raise Invalid()
    return a


def number(text):
    try:
        return float(text)
    except ValueError:
        raise Invalid()


def fault_word(name, a):
    if a.fault or a.interlock_open:
        return FAULT_CODES.get(name, 2048)  # bit 11: ESTOP input, as the users' code reads it
    return 0


def movable(name, a):
    if fault_word(name, a) or not a.servo:
        raise Fault()


def handle(line):
    table.update()
    try:
        m = re.fullmatch(r"\s*(\w+)\s*\(\s*(\w+)\s*\)\s*", line)
        if m:
            what, name = m.group(1).upper(), m.group(2).upper()
            a = axis_of(name)
            if what == "PFBKPROG":
                return ["%%%.6f" % table_peer.wrap_180(a.angle)]
            if what == "VFBK":
                return ["%%%.6f" % a.rate]
            if what == "AXISFAULT":
                return ["%%%d" % fault_word(name, a)]
            if what == "AXISSTATUS":
                word = 0
                if a.servo and not fault_word(name, a):
                    word |= 1
                settled = a.mode in ("position", "rest") and abs(a.rate) < 1e-9
                if a.mode == "position":
                    settled = settled and abs(table_peer.wrap_180(a.target - a.angle)) < 1e-6
                if settled:
                    word |= 4
                if abs(a.rate) > 0.0:
                    word |= 8
                return ["%%%d" % word]
            raise Invalid()
        words = line.split()
        head = words[0].upper()
        if head == "WAIT":
            return ["%"]
        if head == "RAMP":
            if words[1].upper() == "MODE":
                axis_of(words[2])
                return ["%"]
            if words[1].upper() == "RATE":
                a = axis_of(words[2])
                a.max_accel = number(words[3])
                return ["%"]
            raise Invalid()
        name = words[1].upper()
        a = axis_of(name)
        if head == "ENABLE":
            if fault_word(name, a):
                raise Fault()
            a.servo = True
            if a.mode == "off":
                a.mode = "rest"
            return ["%"]
        if head == "DISABLE":
            a.servo = False
            a.halt()
            return ["%"]
        if head == "FAULTACK":
            if a.interlock_open and not a.cause_present:
                a.interlock_open = False
                a.interlock_why = ""
            if a.fault and not a.cause_present:
                a.fault = ""
            return ["%"]
        if head == "ABORT":
            if a.mode != "off":
                a.demand_rate = 0.0
                a.mode = "rest"
            return ["%"]
        if head == "MOVEABS":
            movable(name, a)
            a.target = table_peer.wrap_180(number(words[2]))
            if len(words) > 4 and words[3].upper() == name + "F":
                a.max_rate = number(words[4])
            a.mode = "position"
            return ["%"]
        if head == "FREERUN":
            movable(name, a)
            if words[2].upper() == "STOP":
                a.demand_rate = 0.0
                a.mode = "rest"
            else:
                a.demand_rate = number(words[2])
                a.mode = "rate"
            return ["%"]
        raise Invalid()
    except (Invalid, IndexError):
        return ["!"]
    except Fault:
        return ["#"]


if __name__ == "__main__":
    table_peer.run(table, handle, ending=b"\n", split=b"\r\n")
