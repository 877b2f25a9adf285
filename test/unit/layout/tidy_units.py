#!/usr/bin/env python3
"""The unity files of check_tidy.sh: one per target among FOLDER's translation units (its K-th of N shares).

usage: tidy_units.py COMPILE_COMMANDS SOURCE_DIR FOLDER K/N WORK_DIR
Writes WORK_DIR/unit_<i>.cpp (an #include of each file of one target, in the database's order) and
WORK_DIR/compile_commands.json (each unity file with its target's compile command); prints "COUNT PATH" per unity
file. Files of one target share one command but for their own -o and -c, which is how they are grouped.
"""
import json
import os
import re
import shlex
import sys


def main():
    db_path, src, folder, share, work = sys.argv[1:6]
    k, n = (int(x) for x in share.split("/"))
    pattern = re.compile(re.escape(f"{src}/{folder}/") + r".+\.cpp$")
    entries = {}
    for entry in json.load(open(db_path, encoding="utf-8")):
        if pattern.match(entry["file"]) and entry["file"] not in entries:
            entries[entry["file"]] = entry
    files = sorted(entries)
    mine = [f for i, f in enumerate(files) if i % n + 1 == k]

    groups = {}  # (directory, target, command without -o and -c) -> files
    for f in mine:
        entry = entries[f]
        args = shlex.split(entry["command"]) if "command" in entry else list(entry["arguments"])
        kept, target, skip = [], "", False
        for i, arg in enumerate(args):
            if skip:
                skip = False
                continue
            if arg in ("-o", "-c"):
                skip = True
                if arg == "-o":
                    target = args[i + 1].split(".dir/")[0]
                continue
            kept.append(arg)
        groups.setdefault((entry["directory"], target, tuple(kept)), []).append(f)

    database = []
    for i, ((directory, _, args), group) in enumerate(groups.items()):
        unit = os.path.join(work, f"unit_{i}.cpp")
        with open(unit, "w", encoding="utf-8") as out:
            out.write("".join(f'#include "{f}"\n' for f in group))
        command = shlex.join(list(args) + ["-c", unit])
        database.append({"directory": directory, "command": command, "file": unit})
        print(len(group), unit)
    with open(os.path.join(work, "compile_commands.json"), "w", encoding="utf-8") as out:
        json.dump(database, out, indent=1)


if __name__ == "__main__":
    main()
