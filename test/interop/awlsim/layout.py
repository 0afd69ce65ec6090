#!/usr/bin/env python3
"""Lays out STEP 7 DB and UDT sources with awlsim and prints what it found.

awlsim (https://bues.ch/h/awlsim, GPL) is an S7-300/400 soft PLC written
independently of plcwire. This script is ours: it only calls awlsim's library
(its AWL parser, then the CPU's build, which sizes every DB and UDT) and
reads the offsets awlsim gave each member. test/interop/symbols-awlsim.test.js
compares them with compileSymbols().

Usage:
  layout.py FILE.awl...   one program made of the files; prints one result
  layout.py --batch       reads [{"id": ..., "source": "..."}, ...] as JSON on
                          stdin, builds each source as a program of its own,
                          prints [{"id": ..., <result> or "error": "..."}]

A result is {"blocks": [{"kind": "db" | "udt", "number": n, "length": bytes,
"instanceOf": m (a DB of UDT m), "members": [...]}]}; a member is
{"name": "Motor.Speed", "type": "REAL", "kind": "elementary" | "array" |
"struct", "byte": 6, "bit": null (0-7 for BOOL), "size": bytes}, in the
order of the block, a struct or array before what it holds.

What awlsim 0.77.1 cannot read is rewritten first, each time into what STEP 7
means by it, so that the layout is awlsim's own:
  - start values are removed (the `:= ...` of a declaration and the
    assignments of BEGIN): awlsim refuses a BEGIN assignment to a member of a
    UDT ("assigns field ... but does not declare it"), and no start value
    moves a member;
  - `DATA_BLOCK DB n` followed by `UDT m` (a DB that is an instance of a
    UDT) is not a form awlsim's parser knows: the block is taken out and
    reported with the members and length awlsim gives UDT m;
  - `ARRAY [..] OF UDT m` is an array awlsim cannot size ("width ... is
    undefined"): it is written as an array of a STRUCT with UDT m's members,
    which is what a UDT is, a named STRUCT.
"""

import json
import re
import sys

from awlsim_loader.common import *  # noqa: F401,F403  (awlsim's own loader: its pure-Python or Cython build)
from awlsim_loader.core import *  # noqa: F401,F403
from awlsim_loader.awlcompiler import *  # noqa: F401,F403

BLOCK = re.compile(r"\b(TYPE|DATA_BLOCK)\b(.*?)\bEND_(?:TYPE|DATA_BLOCK)\b", re.S | re.I)
UDT_HEADER = re.compile(r"^\s*UDT\s*(\d+)", re.I)
DB_OF_UDT = re.compile(r"^\s*DB\s*(\d+)\b(?:(?!\bSTRUCT\b).)*?\bUDT\s*(\d+)\s*(?:BEGIN\b)", re.S | re.I)
ARRAY_OF_UDT = re.compile(r"(\bARRAY\s*\[[^\]]*\]\s*OF\s*)UDT\s*(\d+)\s*;", re.I)


def strip_comments(text):
    """Line comments (//) out, keeping the line structure."""
    return re.sub(r"//[^\n]*", "", text)


def strip_start_values(text):
    text = re.sub(r"(\bBEGIN\b).*?(\bEND_DATA_BLOCK\b)", r"\1\n\2", text, flags=re.S | re.I)
    # `:= value ;` in a declaration; a STRING start value may hold a ';' between its quotes.
    return re.sub(r":=(?:'[^']*'|[^;'])*;", ";", text)


def udt_bodies(text):
    """UDT number -> the text between the first STRUCT and the last END_STRUCT of TYPE UDT n."""
    bodies = {}
    for m in BLOCK.finditer(text):
        if m.group(1).upper() != "TYPE":
            continue
        header = UDT_HEADER.match(m.group(2))
        if not header:
            continue
        body = m.group(2)
        start = re.search(r"\bSTRUCT\b", body, re.I)
        end = [e for e in re.finditer(r"\bEND_STRUCT\b", body, re.I)]
        if start and end:
            bodies[int(header.group(1))] = body[start.end():end[-1].start()]
    return bodies


def inline_udt_arrays(text, bodies):
    """ARRAY [..] OF UDT m -> ARRAY [..] OF STRUCT <members of UDT m> END_STRUCT (repeated for UDTs in UDTs)."""
    for _ in range(32):

        def expand(m):
            number = int(m.group(2))
            if number not in bodies:
                return m.group(0)  # awlsim reports the unknown UDT itself
            return "%sSTRUCT %s END_STRUCT ;" % (m.group(1), bodies[number])

        rewritten = ARRAY_OF_UDT.sub(expand, text)
        if rewritten == text:
            return text
        text = rewritten
        bodies = {n: ARRAY_OF_UDT.sub(expand, b) for n, b in bodies.items()}
    return text


def prepare(text):
    """The source awlsim can read, and the DBs taken out of it as {db number: UDT number}."""
    text = strip_start_values(strip_comments(text))
    instances = {}
    kept = []
    last = 0
    for m in BLOCK.finditer(text):
        of_udt = DB_OF_UDT.match(m.group(2)) if m.group(1).upper() == "DATA_BLOCK" else None
        if of_udt:
            instances[int(of_udt.group(1))] = int(of_udt.group(2))
            kept.append(text[last:m.start()])
            last = m.end()
    kept.append(text[last:])
    text = "".join(kept)
    return inline_udt_arrays(text, udt_bodies(text)), instances


def members(struct):
    """The named fields of an awlsim AwlStruct as our member records; padding and a STRING's bytes left out."""
    out = []
    string_end = -1  # a STRING's length bytes and characters follow its own field
    for field in struct.fields:
        offset = field.offset
        if offset.byteOffset < string_end:
            continue
        dtype = field.dataType
        if field.name is None or dtype.type == AwlDataType.TYPE_VOID:
            continue
        kind = "elementary"
        if dtype.type == AwlDataType.TYPE_ARRAY:
            kind = "array"
        elif dtype.type in (AwlDataType.TYPE_STRUCT, AwlDataType.TYPE_UDT_X):
            kind = "struct"
        size = (dtype.width + 7) // 8
        if dtype.type == AwlDataType.TYPE_STRING:
            string_end = offset.byteOffset + size
        out.append(
            {
                "name": str(field.name),
                "type": str(dtype),
                "kind": kind,
                "byte": offset.byteOffset,
                "bit": offset.bitOffset if dtype.type == AwlDataType.TYPE_BOOL else None,
                "size": size,
            }
        )
    return out


def layout(text):
    source, instances = prepare(text)
    parser = AwlParser()
    parser.parseText(source)
    sim = AwlSim()
    sim.load(parser.getParseTree())
    sim.build()
    cpu = sim.getCPU()
    udts = {udt.index: udt for udt in cpu.allUDTs()}
    blocks = []
    for db in cpu.allDBs():
        if db.index == 0:  # awlsim's own DB 0
            continue
        blocks.append({"kind": "db", "number": db.index, "length": db.struct.getSize(), "members": members(db.struct)})
    for number, udt_number in instances.items():
        udt = udts.get(udt_number)
        if udt is None:
            raise AwlSimError("DB %d is an instance of UDT %d, which is not among the sources" % (number, udt_number))
        blocks.append(
            {
                "kind": "db",
                "number": number,
                "instanceOf": udt_number,
                "length": udt._struct.getSize(),
                "members": members(udt._struct),
            }
        )
    for number, udt in udts.items():
        blocks.append({"kind": "udt", "number": number, "length": udt._struct.getSize(), "members": members(udt._struct)})
    blocks.sort(key=lambda b: (b["kind"], b["number"]))
    return {"blocks": blocks}


def error_text(err):
    return " ".join(str(err).split())


def main(argv):
    if argv[1:] == ["--batch"]:
        results = []
        for case in json.load(sys.stdin):
            try:
                results.append(dict(id=case["id"], **layout(case["source"])))
            except Exception as err:  # awlsim's errors, and its crashes on what it does not support
                results.append({"id": case["id"], "error": "%s: %s" % (type(err).__name__, error_text(err))})
        json.dump(results, sys.stdout)
        return 0
    if len(argv) < 2 or argv[1].startswith("-"):
        sys.stderr.write(__doc__)
        return 2
    text = ""
    for name in argv[1:]:
        with open(name, "rb") as f:
            # STEP 7 writes its sources in the Windows code page (latin-1 for what matters here).
            text += f.read().decode("latin-1") + "\n"
    try:
        json.dump(dict(awlsim=VERSION_STRING, **layout(text)), sys.stdout, indent=1)
    except (AwlParserError, AwlSimError) as err:
        sys.stderr.write("awlsim: %s\n" % error_text(err))
        return 1
    sys.stdout.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
