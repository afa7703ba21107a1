"""An Ideal Aerosmith rate table controller as users' public code shows its serial command
language (a 1270VS control panel, Python: aerosmith/commands.py and communication.py), for
LineTable's tests, served on TCP instead of the 9600-baud serial line.

What it speaks, from that code:
- three-letter commands with a value (ACL acceleration, JOG rate in deg/s within -360..360,
  SRV motor on (1) / off (0), STO stop, HOM home), queries are the command followed by '?';
- every command is answered by the response terminator CR LF '>' CR LF, a query by its value
  then that terminator; any other answer means the command failed.
Left open by the material, and read here as the aerosmith set reads it: the axis is the first
argument ('JOG 2,10.0', 'POS? 1'); POS moves to an angle; 'SRV? N' answers 1 (motor on) or 0
(off: an interlock or a fault switched it off; 'SRV N,1' switches it on again unless the cause
is present); a refused command is answered by the
controller's own text before the prompt ('AXIS 2 FAULT: ...'); commands end with CR or LF.
"""

import os
import sys

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import table_peer  # noqa: E402

table = table_peer.Table(["1", "2"])
PROMPT = "\r\n>"  # with the line ending: CR LF > CR LF


class Refused(Exception):
    pass


def axis_of(text):
    a = table.axes.get(text.strip())
    if a is None:
        raise Refused("INVALID AXIS %s" % text.strip())
    return a


def number(text):
    try:
        return float(text)
    except ValueError:
        raise Refused("INVALID PARAMETER %s" % text.strip())


def ready(name, a):
    if a.fault:
        raise Refused("AXIS %s FAULT: %s" % (name, a.fault))
    if a.interlock_open:
        raise Refused("AXIS %s INTERLOCK OPEN: %s" % (name, a.interlock_why))
    if not a.servo:
        raise Refused("AXIS %s MOTOR OFF" % name)


def handle(line):
    now = table.update()
    head = line[:3].upper()
    query = line[3:4] == "?"
    args = [x.strip() for x in line[4 if query else 3:].split(",") if x.strip()]
    try:
        if not args:
            raise Refused("MISSING AXIS")
        name = args[0]
        a = axis_of(name)
        if query:
            if head == "POS":
                return ["%.4f" % table_peer.wrap_180(a.angle) + PROMPT]
            if head == "JOG":
                return ["%.4f" % a.demand_rate + PROMPT]
            if head == "ACL":
                return ["%.4f" % a.max_accel + PROMPT]
            if head == "SRV":
                return [("1" if a.usable() else "0") + PROMPT]
            raise Refused("INVALID COMMAND %s?" % head)
        if head == "STO":
            if a.mode != "off":
                a.demand_rate = 0.0
                a.mode = "rest"
            return [PROMPT]
        if head == "ACL":
            value = number(args[1])
            if value <= 0:
                raise Refused("ACL OUT OF RANGE")
            a.max_accel = value
            return [PROMPT]
        if head == "SRV":
            on = number(args[1]) != 0
            if on:
                if a.fault:
                    raise Refused("AXIS %s FAULT: %s" % (name, a.fault))
                if a.interlock_open and a.cause_present:
                    raise Refused("AXIS %s INTERLOCK OPEN: %s" % (name, a.interlock_why))
                a.interlock_open = False
                a.interlock_why = ""
                a.servo = True
                if a.mode == "off":
                    a.mode = "rest"
            else:
                a.servo = False
                a.halt()
            return [PROMPT]
        if head == "JOG":
            ready(name, a)
            rate = number(args[1])
            if abs(rate) > 360.0:
                raise Refused("JOG OUT OF RANGE")
            a.demand_rate = rate
            a.mode = "rate"
            return [PROMPT]
        if head == "POS":
            ready(name, a)
            a.target = table_peer.wrap_180(number(args[1]))
            a.mode = "position"
            return [PROMPT]
        raise Refused("INVALID COMMAND %s" % head)
    except (Refused, IndexError) as e:
        return [(str(e) if isinstance(e, Refused) else "MISSING PARAMETER") + PROMPT]


if __name__ == "__main__":
    # Replies end with CR LF; the prompt line follows a query's value.
    table_peer.run(table, handle, ending=b"\r\n", split=b"\r\n")
