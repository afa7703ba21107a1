"""An Actidyn rate table controller as one lab's public C# client shows its TCP command
language (namespace ActidinController: Form1.cs, ActidynCmd.cs), for LineTable's tests.

What it speaks, from that client:
- lines ended by LF; 'RMT 0' (remote), 'USR 0,...' (user), 'ALC 0' (clear the accumulated
  alarms);
- 'MOD <axis>,POS|RAT|SIN|STP|OFF' selects the mode, 'MOD <axis>,1' switches the servo on,
  'MOD <axis>,?' / 'MOD &,?' ask it;
- 'POS <axis>,<deg>,<deg/s>', 'RAT <axis>,<deg/s>,<accel>', 'SIN <axis>,<ampl>,<Hz>,<phase>';
- 'PRV <axis>,?' / 'PRV &,?' ask position, rate and acceleration;
- a query is answered '<count>, <v1>, ..., <vN>' (the client checks the count before the first
  comma and compares modes with ' OFF', ' POS', ... : a blank before each value).
Left open, and read as the actidyn set reads it: commands that set something are not answered;
a refused command is answered by one line 'ERROR <the controller's words>'.
"""

import os
import sys

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import table_peer  # noqa: E402

table = table_peer.Table(["1", "2"])


class Refused(Exception):
    pass


def axes_of(text):
    text = text.strip()
    if text == "&":
        return list(table.axes.items())
    a = table.axes.get(text)
    if a is None:
        raise Refused("AXIS %s DOES NOT EXIST" % text)
    return [(text, a)]


def number(text):
    try:
        return float(text)
    except ValueError:
        raise Refused("BAD PARAMETER %s" % text.strip())


def mode_word(a):
    if not a.servo or a.interlock_open or a.fault or a.mode == "off":
        return "OFF"
    return {"rest": "STP", "position": "POS", "rate": "RAT", "sine": "SIN"}[a.mode]


def ready(name, a):
    if a.fault:
        raise Refused("AXIS %s ALARM %s" % (name, a.fault))
    if a.interlock_open or not a.servo:
        raise Refused("AXIS %s DRIVE OFF%s" % (name, (": " + a.interlock_why) if a.interlock_why else ""))


def reply(values):
    return ["%d," % len(values) + ",".join(" " + v for v in values)]


def handle(line):
    now = table.update()
    head, _, rest = line.partition(" ")
    head = head.upper()
    args = [x.strip() for x in rest.split(",")]
    try:
        if head in ("RMT", "USR", "LOC"):
            return [] if not (len(args) > 1 and args[-1] == "?") else reply(["1"])
        if head == "ALC":
            for a in table.axes.values():
                if a.fault and not a.cause_present:
                    a.fault = ""
            return []
        targets = axes_of(args[0])
        if len(args) > 1 and args[1] == "?":
            if head == "MOD":
                return reply([mode_word(a) for _, a in targets])
            if head == "PRV":
                values = []
                for _, a in targets:
                    values += ["%.4f" % table_peer.wrap_180(a.angle), "%.4f" % a.rate, "0.0000"]
                return reply(values)
            raise Refused("UNKNOWN QUERY %s" % head)
        for name, a in targets:
            if head == "MOD":
                word = args[1].upper()
                if word == "OFF":
                    a.servo = False
                    a.halt()
                elif word == "1":
                    if a.fault:
                        raise Refused("AXIS %s ALARM %s" % (name, a.fault))
                    if a.interlock_open and a.cause_present:
                        raise Refused("AXIS %s DRIVE OFF: %s" % (name, a.interlock_why))
                    a.interlock_open = False
                    a.interlock_why = ""
                    a.servo = True
                    a.mode = "rest"
                else:
                    ready(name, a)
                    if word == "POS":
                        a.target = table_peer.wrap_180(a.angle)
                        a.mode = "position"
                    elif word == "RAT":
                        a.demand_rate = 0.0
                        a.mode = "rate"
                    elif word == "SIN":
                        a.sine_amplitude = 0.0
                        a.start_sine(0.0, 0.0, 0.0, now)
                    elif word == "STP":
                        a.demand_rate = 0.0
                        a.mode = "rest"
                    else:
                        raise Refused("UNKNOWN MODE %s" % word)
            elif head == "POS":
                ready(name, a)
                if a.mode != "position":
                    raise Refused("AXIS %s NOT IN POS MODE" % name)
                a.target = table_peer.wrap_180(number(args[1]))
                if len(args) > 2 and number(args[2]) > 0:
                    a.max_rate = number(args[2])
            elif head == "RAT":
                ready(name, a)
                if a.mode != "rate":
                    raise Refused("AXIS %s NOT IN RAT MODE" % name)
                a.demand_rate = number(args[1])
                if len(args) > 2 and number(args[2]) > 0:
                    a.max_accel = number(args[2])
            elif head == "SIN":
                ready(name, a)
                if a.mode != "sine":
                    raise Refused("AXIS %s NOT IN SIN MODE" % name)
                a.start_sine(number(args[1]), number(args[2]),
                             number(args[3]) if len(args) > 3 else 0.0, now)
            else:
                raise Refused("UNKNOWN COMMAND %s" % head)
        return []
    except (Refused, IndexError) as e:
        return ["ERROR " + (str(e) if isinstance(e, Refused) else "MISSING PARAMETER")]


if __name__ == "__main__":
    table_peer.run(table, handle, ending=b"\n", split=b"\r\n")
