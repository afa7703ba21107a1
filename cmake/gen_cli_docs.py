#!/usr/bin/env python3
"""Man page and bash completion of a calstand program, from the program's own --help.

Run at build time (cmake/CalstandCliDocs.cmake) on the programs just built, so that neither can
drift from the options. Walks the command tree: `PROG --help`, then `PROG SUB --help` for each
subcommand the help lists, and so on down. Reads CLI11's help layout: a description line,
`Usage:`, then the sections `Positionals:`, `Options:` and `Subcommands:` (or the task headings
the top-level help groups its subcommands under), one entry a line,
the name column padded to the description (a long name puts it on the next line, indented).

  gen_cli_docs.py PROGRAM NAME SECTION VERSION MAN_OUT COMPLETION_OUT [--extra FILE]

--extra: a file of roff appended before SEE ALSO (FILES, ENVIRONMENT, ...).
"""
import argparse
import re
import subprocess
import sys

SECTIONS = ("Positionals:", "Options:", "Subcommands:")


class Command:
    def __init__(self, path):
        self.path = path  # subcommand words below the program
        self.description = ""
        self.usage = ""
        self.positionals = []  # (name, description)
        self.options = []  # (spec, description): spec is the help's name column
        self.subcommands = []  # Command
        self.footer = []  # lines after the sections (a table, examples): kept as printed


def split_entry(line):
    """'  --db TEXT=x.db     SQLite file' -> ('--db TEXT=x.db', 'SQLite file')."""
    body = line.strip()
    m = re.match(r"(\S(?:.*?\S)?)(?:\s{2,}(.*))?$", body)
    return m.group(1), (m.group(2) or "").strip()


def parse_help(text, path, where):
    cmd = Command(path)
    lines = text.splitlines()
    if not lines:
        raise SystemExit(f"{where}: --help printed nothing")
    section = None
    seen_example = False  # the footer's example: no task heading after it
    for i, line in enumerate(lines):
        if i == 0 and not line.startswith("Usage:"):
            cmd.description = line.strip()
            continue
        if line.startswith("Usage:"):
            cmd.usage = line[len("Usage:"):].strip()
            section = None
            continue
        if line in SECTIONS:
            section = line
            continue
        if line in ("Example:", "Examples:"):
            seen_example = True
        if (not seen_example and "SUBCOMMAND" in cmd.usage and line.endswith(":")
                and not line.startswith(" ")):
            # `calstand --help` lists its subcommands under task headings ("Run a station:"),
            # each a Subcommands: section of its own (cli/src/help_layout.cpp).
            section = "Subcommands:"
            continue
        if section == "footer" or (section is not None and not line.startswith(" ")):
            section = "footer"  # a footer: every line from here on, blank ones too
            cmd.footer.append(line.rstrip())
            continue
        if not line.strip():
            continue
        if section is None:
            # A footer or a description of more lines: kept with the description.
            cmd.description = (cmd.description + " " + line.strip()).strip()
            continue
        entries = {"Positionals:": cmd.positionals, "Options:": cmd.options,
                   "Subcommands:": cmd.subcommands}[section]
        if line.startswith("   ") and entries and section != "Subcommands:":
            # The description of a long name, on its own line.
            name, desc = entries[-1]
            entries[-1] = (name, (desc + " " + line.strip()).strip())
            continue
        if line.startswith("   ") and section == "Subcommands:" and entries:
            entries[-1] = (entries[-1][0], (entries[-1][1] + " " + line.strip()).strip())
            continue
        entries.append(split_entry(line))
    return cmd


def walk(program, path=()):
    where = " ".join((program,) + tuple(path)) + " --help"
    out = subprocess.run([program, *path, "--help"], capture_output=True, text=True, timeout=60)
    if out.returncode != 0:
        raise SystemExit(f"{where}: exit {out.returncode}: {out.stderr.strip()}")
    cmd = parse_help(out.stdout, list(path), where)
    subs = cmd.subcommands
    cmd.subcommands = [walk(program, tuple(path) + (name,)) for name, _ in subs]
    for sub, (_, desc) in zip(cmd.subcommands, subs):
        if not sub.description:
            sub.description = desc
    return cmd


def option_names(spec):
    """'-o,--out TEXT REQUIRED' -> ['-o', '--out']; takes a value when a type follows."""
    first = spec.split(" ", 1)[0]
    names = [n for n in first.split(",") if n.startswith("-")]
    rest = spec[len(first):].strip()
    takes_value = bool(re.match(r"(TEXT|INT|UINT|FLOAT|NUMBER|FILE|DIR|PATH|ENUM|\[|\{|[A-Z]+\b)",
                                rest)) and not rest.startswith(("Excludes", "Needs"))
    return names, takes_value


def roff(text):
    text = text.replace("\\", "\\e").replace("-", "\\-")
    return text


def roff_line(text):
    text = roff(text)
    if text.startswith((".", "'")):
        text = "\\&" + text
    return text


def man_page(root, name, section, version, extra):
    prog = name
    out = [f'.TH {name.upper()} {section} "" "calstand {version}" "calstand"',
           ".SH NAME", f"{roff(name)} \\- {roff_line(strip_prefix(root.description, name))}",
           ".SH SYNOPSIS", f".B {roff(prog)}", roff_line(usage_tail(root.usage)),
           ".SH DESCRIPTION", roff_line(root.description)]

    def entries(cmd):
        if cmd.positionals:
            out.append(".PP\nArguments:")
            for spec, desc in cmd.positionals:
                out.extend([".TP", f".B {roff(spec)}", roff_line(desc)])
        if cmd.options:
            if cmd.positionals:
                out.append(".PP\nOptions:")
            for spec, desc in cmd.options:
                out.extend([".TP", f".B {roff(spec)}", roff_line(desc)])

    def footer(cmd):
        while cmd.footer and not cmd.footer[-1]:
            cmd.footer.pop()
        if cmd.footer:
            out.extend([".PP", ".nf"] + [roff_line(l) for l in cmd.footer] + [".fi"])

    out.append(".SH OPTIONS")
    entries(root)
    footer(root)
    if root.subcommands:
        out.append(".SH COMMANDS")
        stack = list(reversed(root.subcommands))
        while stack:
            cmd = stack.pop()
            out.append(f".SS {roff(' '.join([prog] + cmd.path))}")
            out.append(roff_line(cmd.description))
            out.append(".PP")
            out.append(f"Usage: {roff_line(' '.join([prog] + cmd.path) + ' ' + usage_tail(cmd.usage, len(cmd.path)))}")
            entries(cmd)
            footer(cmd)
            stack.extend(reversed(cmd.subcommands))
    if extra:
        out.append(extra.rstrip("\n"))
    see = [(n, s) for n, s in (("calstand", "1"), ("calstandd", "8"), ("systemctl", "1"),
                               ("journalctl", "1")) if n != name]
    out.append(".SH SEE ALSO")
    out.extend(f".BR {n} ({s}){',' if i + 1 < len(see) else ''}" for i, (n, s) in enumerate(see))
    out.append(".PP")
    out.append("The documentation in /usr/share/doc/calstand/ and the schemas in "
               "/usr/share/calstand/schemas/.")
    return "\n".join(out) + "\n"


def strip_prefix(description, name):
    prefix = name + ": "
    return description[len(prefix):] if description.startswith(prefix) else description


def usage_tail(usage, depth=0):
    """The usage line without the program's path (the build directory's, at build time) and
    the `depth` subcommand words after it."""
    return " ".join(usage.split(" ")[1 + depth:])


def bash_word(s):
    return "'" + s.replace("'", "'\\''") + "'"


def completion(root, name):
    fn = "_" + re.sub(r"[^A-Za-z0-9_]", "_", name)
    subs, opts, valued = {}, {}, {}

    def visit(cmd):
        key = " ".join(["_"] + cmd.path)  # "_": the program itself (bash keys cannot be empty)
        subs[key] = " ".join(s.path[-1] for s in cmd.subcommands)
        names, with_value = [], []
        for spec, _ in cmd.options:
            n, v = option_names(spec)
            names.extend(n)
            if v:
                with_value.extend(n)
        opts[key] = " ".join(names)
        valued[key] = " ".join(with_value)
        for s in cmd.subcommands:
            visit(s)

    visit(root)

    def table(var, data):
        rows = "\n".join(f"  [{bash_word(k)}]={bash_word(v)}" for k, v in sorted(data.items()))
        return f"declare -gA {var}=(\n{rows}\n)"

    return f"""# bash completion of {name}: its subcommands and their options.
# Generated at build time from `{name} ... --help` by cmake/gen_cli_docs.py; do not edit.
{table(fn + "_subcommands", subs)}
{table(fn + "_options", opts)}
{table(fn + "_valued", valued)}

{fn}() {{
  local cur="${{COMP_WORDS[COMP_CWORD]}}" prev="" path="_" word i
  [ "$COMP_CWORD" -gt 0 ] && prev="${{COMP_WORDS[COMP_CWORD-1]}}"
  # The subcommand path so far: each word that names a subcommand of the path before it.
  for ((i = 1; i < COMP_CWORD; i++)); do
    word="${{COMP_WORDS[i]}}"
    case " ${{{fn}_subcommands[$path]}} " in
      *" $word "*) path="$path $word" ;;
    esac
  done
  # After an option that takes a value: file names (most values are files).
  if [ -n "$prev" ] && [[ " ${{{fn}_valued[$path]}} " == *" $prev "* ]]; then
    COMPREPLY=($(compgen -f -- "$cur"))
    return
  fi
  if [[ "$cur" == -* ]]; then
    COMPREPLY=($(compgen -W "${{{fn}_options[$path]}}" -- "$cur"))
  else
    COMPREPLY=($(compgen -W "${{{fn}_subcommands[$path]}}" -- "$cur"))
    [ ${{#COMPREPLY[@]}} -eq 0 ] && COMPREPLY=($(compgen -f -- "$cur"))
  fi
}}
complete -o filenames -F {fn} {name}
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("program")
    ap.add_argument("name")
    ap.add_argument("section")
    ap.add_argument("version")
    ap.add_argument("man_out")
    ap.add_argument("completion_out")
    ap.add_argument("--extra")
    a = ap.parse_args()
    root = walk(a.program)
    extra = open(a.extra, encoding="utf-8").read() if a.extra else ""
    with open(a.man_out, "w", encoding="utf-8") as f:
        f.write(man_page(root, a.name, a.section, a.version, extra))
    with open(a.completion_out, "w", encoding="utf-8") as f:
        f.write(completion(root, a.name))
    return 0


if __name__ == "__main__":
    sys.exit(main())
