"""An Acutronic ACUTROL3000 as its Command Language manual describes it (TM-8004-C, published
with users' code in github.com/IEAv-EFO/acutrol3000), for LineTable's tests: a two-axis table
on TCP (TM-9384C: the host connects to the real-time computer's port; here a free port).

What it speaks, from the manual:
- program messages of commands joined by ';', headers of colon-separated mnemonics that may be
  shortened (':Demand:Position 3,10.5' = ':Dem:Pos 3,10.5' = ':D:P 3,10.5', 2.1); a header
  without its leading colon stays in the subsystem of the previous one (2.2.2, 2.3);
- *IDN? answered '<manufacturer>,<model>,<serial number>,<software level>' (3.4);
- :Mode:Position/Rate/Synthesis/Off <axis>, :Mode? <axis> answered one letter (4.7);
- :Demand:Position/Rate <axis>,<value>, :Demand:Oscillator <axis>,<magnitude>,<Hz>,<phase>
  (4.3.4-4.3.6); Synthesis oscillates about the position demand (4.7.6);
- :Limit:Rate/Acceleration <mode>,<axis>,<value> and their queries (4.6.2, 4.6.8);
- :Read:Position?/Rate? <axis> (4.10.4-4.10.5), ASCII floats after :Utility:Format FLOAT (4.14.1);
- :Interlock:Close/Open <axis>, :Interlock:Reset, :Interlock? <axis> answered Close, Open or
  Fault (4.5; 4.5.3's states);
- only queries are answered (2: 'The IEEE488 interface protocol only receives a response if the
  command requests data'); several queries in one message are answered in one line joined by
  ';' (4.10.4's example).
Errors: the manual's error section is 'TBD' (6.1); an invalid axis or parameter 'sets the
PARAMETER OUT OF RANGE bit'. This peer answers a refused message with one line
'Error: <why>' (the cautious reading the acutrol3000 set makes) and stops at that command.
"""

import os
import sys

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import table_peer  # noqa: E402

ROOT = ["DEMAND", "INTERLOCK", "LIMIT", "MODE", "READ", "UTILITY", "QUERY"]
SUB = {
    "DEMAND": ["POSITION", "RATE", "OSCILLATOR", "ACCELERATION"],
    "INTERLOCK": ["CLOSE", "OPEN", "RESET"],
    "LIMIT": ["RATE", "ACCELERATION", "HIPOSITION", "LOPOSITION", "VTRIP"],
    "MODE": ["POSITION", "RATE", "ARATE", "SYNTHESIS", "OFF", "TRACK", "HOME"],
    "READ": ["POSITION", "RATE", "ACCELERATION"],
    "UTILITY": ["FORMAT"],
}
LIMIT_MODES = {"P": "position", "R": "rate", "S": "synthesis", "O": "off", "A": "abort",
               "T": "track"}
FACTORY_RATE_LIMIT = 1000.0  # the Limit:Absolute this unit left the factory with [deg/s]

table = table_peer.Table(["1", "2"])
state = {"format": "FLOAT"}


class Refused(Exception):
    pass


def match(mnemonic, names):
    m = mnemonic.upper()
    for n in names:
        if n.startswith(m):
            return n
    raise Refused("undefined header '%s'" % mnemonic)


def axis_of(arg):
    a = table.axes.get(arg.strip())
    if a is None:
        raise Refused("parameter out of range: axis '%s'" % arg.strip())
    return a


def number(arg):
    try:
        return float(arg)
    except ValueError:
        raise Refused("parameter out of range: '%s' is not a number" % arg)


def servoed(axis_name, a):
    if a.interlock_open or a.fault:
        raise Refused("axis %s not servoed: interlock %s" % (axis_name, "Fault"))


def mode_letter(a):
    if a.interlock_open or a.fault or a.mode == "off":
        return "A"  # aborted: the axis shut down
    return {"rest": "O", "position": "P", "rate": "R", "sine": "S"}[a.mode]


def interlock_word(a):
    if a.interlock_open:
        return "Fault"
    return "Close"


def execute(path, query, args, now):
    """One command; returns its reply text (queries) or None."""
    top = path[0]
    if top == "MODE" and len(path) == 1 and query:
        return mode_letter(axis_of(args[0]))
    if top == "MODE":
        name = args[0].strip()
        a = axis_of(name)
        what = path[1]
        if what == "OFF":
            if not (a.interlock_open or a.fault):
                a.mode = "rest"
            return None
        servoed(name, a)
        if what == "POSITION":
            a.mode = "position"
        elif what in ("RATE", "ARATE"):
            a.demand_rate = 0.0
            a.mode = "rate"
        elif what == "SYNTHESIS":
            a.start_sine(a.sine_amplitude, a.sine_frequency, a.sine_phase_deg, now)
            a.sine_centre = a.target
        else:
            raise Refused("mode %s not available" % what)
        return None
    if top == "DEMAND":
        name = args[0].strip()
        a = axis_of(name)
        what = path[1]
        if what == "POSITION":
            a.target = table_peer.wrap_180(number(args[1]))
        elif what == "RATE":
            r = number(args[1])
            if abs(r) > FACTORY_RATE_LIMIT:
                raise Refused("parameter out of range: rate %g" % r)
            a.demand_rate = r
        elif what == "OSCILLATOR":
            a.sine_amplitude, a.sine_frequency, a.sine_phase_deg = (number(x) for x in args[1:4])
        return None
    if top == "LIMIT":
        mode = LIMIT_MODES.get(args[0].strip().upper()[:1])
        if mode is None:
            raise Refused("parameter out of range: mode '%s'" % args[0])
        a = axis_of(args[1])
        what = path[1]
        if query:
            return "%.4f" % (a.max_rate if what == "RATE" else a.max_accel)
        value = number(args[2])
        if what == "RATE":
            if value > FACTORY_RATE_LIMIT or value < 0:
                raise Refused("parameter out of range: rate limit %g" % value)
            a.max_rate = value if mode in ("position", "rate", "synthesis") else a.max_rate
        elif what == "ACCELERATION":
            if value <= 0:
                raise Refused("parameter out of range: acceleration limit %g" % value)
            a.max_accel = value if mode in ("position", "rate", "off") else a.max_accel
        return None
    if top == "READ":
        a = axis_of(args[0])
        if path[1] == "POSITION":
            return "%.5f" % table_peer.wrap_180(a.angle)
        if path[1] == "RATE":
            return "%.5f" % a.rate
        return "0.00000"
    if top == "INTERLOCK":
        if len(path) == 1 and query:
            return interlock_word(axis_of(args[0]))
        what = path[1]
        if what == "RESET":
            return None
        a = axis_of(args[0])
        if what == "CLOSE":
            if a.interlock_open and not a.cause_present:
                a.interlock_open = False
                a.interlock_why = ""
                a.mode = "rest"
            if a.fault:
                a.fault = ""
                a.mode = "rest"
        elif what == "OPEN":
            a.interlock_open = True
            a.interlock_why = "opened by command"
            a.halt()
        return None
    if top == "UTILITY":
        if query:
            return state["format"]
        word = args[0].strip().upper()
        state["format"] = "FLOAT" if word.startswith("F") else "BINARY"
        return None
    raise Refused("undefined header")


def handle(line):
    now = table.update()
    replies = []
    subsystem = []
    try:
        for command in line.split(";"):
            command = command.strip()
            if not command:
                continue
            if command.upper() == "*IDN?":
                replies.append("Acutronic USA,Acutrol3000,0,peer-1.0")
                continue
            header, _, rest = command.partition(" ")
            args = [x for x in rest.split(",")] if rest.strip() else []
            query = header.endswith("?")
            header = header.rstrip("?")
            if header.startswith(":"):
                names = [m for m in header[1:].split(":")]
                base = []
            else:
                names = header.split(":")
                base = subsystem
            path = list(base)
            for m in names:
                options = ROOT if not path else SUB.get(path[-1], [])
                path.append(match(m, options))
            subsystem = path[:-1] if len(path) > 1 else path
            reply = execute(path, query, args, now)
            if reply is not None:
                replies.append(reply)
    except Refused as e:
        return ["Error: " + str(e)]
    return [";".join(replies)] if replies else []


if __name__ == "__main__":
    table_peer.run(table, handle, ending=b"\n", split=b"\r\n")
