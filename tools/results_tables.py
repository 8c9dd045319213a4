#!/usr/bin/env python3
"""Writes every table of numbers in README.md and docs/ from the data files in docs/results/.

A table sits between two markers in a Markdown file:

    <!-- table:NAME [cols=a,b,c] [where=col=value] [pivot=key,across,value] [sig=N] -->
    ... generated, never edited by hand ...
    <!-- /table -->

NAME is a data file under docs/results/ without its `.csv` (e.g. `h200/many_lights_scaling`).
`cols` picks and orders columns, `where` keeps the rows whose column equals the value (no
spaces), `pivot=key,across,value` makes a row per `key` and a column per value of `across`, `sig`
rounds numeric cells to N significant digits. The block ends with a line naming the data file
and its device, driver, date, commit and the command that produced it.

A data file is CSV, preceded by `# key: value` lines. Every file needs `device`, `driver`,
`commit`, `date` and `command`. A data file with `# derive: lookup` is a table of pointers: each
row names a `data` file, a `match` column and value, and columns to copy from the matching row
(`error_col`, `time_col`, shown as `rel_mse` and `frame_ms`), so a summary table repeats
measured numbers without retyping them.

    python3 tools/results_tables.py            rewrite the tables in place
    python3 tools/results_tables.py --check    exit 1 naming every table that differs from its data

Python 3 standard library only.
"""

import csv
import io
import math
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "docs" / "results"
REQUIRED = ("device", "driver", "commit", "date", "command")
MARKER = re.compile(r"<!-- table:(\S+)((?:\s+\w+=\S+)*)\s*-->\n(.*?)<!-- /table -->\n", re.S)


class DataError(Exception):
    pass


def read_data(name):
    """(metadata dict, header list, rows as dicts) of docs/results/NAME.csv."""
    path = RESULTS / f"{name}.csv"
    if not path.is_file():
        raise DataError(f"{path.relative_to(ROOT)}: no such data file")
    text = path.read_text(encoding="utf-8")
    meta, body = {}, []
    for line in text.splitlines(keepends=True):
        if not body and line.startswith("#"):
            key, sep, value = line[1:].partition(":")
            if not sep:
                raise DataError(f"{path.relative_to(ROOT)}: metadata line without 'key: value': {line.strip()}")
            meta[key.strip()] = value.strip()
        else:
            body.append(line)
    missing = [k for k in REQUIRED if not meta.get(k)]
    if missing:
        raise DataError(f"{path.relative_to(ROOT)}: metadata lacks {', '.join(missing)}")
    reader = csv.DictReader(io.StringIO("".join(body)))
    if not reader.fieldnames:
        raise DataError(f"{path.relative_to(ROOT)}: no header row")
    rows = list(reader)
    for i, row in enumerate(rows):
        if None in row or any(v is None for v in row.values()):
            raise DataError(f"{path.relative_to(ROOT)}: row {i + 2} has the wrong number of cells")
    return meta, list(reader.fieldnames), rows


def round_cell(cell, sig):
    try:
        x = float(cell)
    except ValueError:
        return cell
    if not math.isfinite(x) or x == 0:
        return cell
    if abs(x) >= 10 ** sig:
        return f"{round(x):d}"
    return f"{x:.{sig}g}"


def derive(meta, header, rows, name):
    """Rows of a lookup table with each pointer replaced by the value it points at."""
    out = []
    for row in rows:
        d_meta, _, d_rows = read_data(row["data"])
        hits = [r for r in d_rows if r.get(row["match"]) == row["value"]]
        if len(hits) != 1:
            raise DataError(
                f"docs/results/{name}.csv: {row['data']} has {len(hits)} rows with {row['match']} = {row['value']}"
            )
        new = dict(row)
        for out_col, src in (("rel_mse", row["error_col"]), ("frame_ms", row["time_col"])):
            if src and src not in hits[0]:
                raise DataError(f"docs/results/{name}.csv: {row['data']} has no column '{src}'")
            new[out_col] = hits[0][src] if src and hits[0][src] else "not measured"
        new["device"] = d_meta["device"]
        new["data"] = f"`docs/results/{row['data']}.csv`"
        out.append(new)
    return out


def pivot(name, header, rows, spec):
    """Rows keyed by one column, a column per value of another, cells from a third."""
    parts = spec.split(",")
    if len(parts) != 3 or any(p not in header for p in parts):
        raise DataError(f"docs/results/{name}.csv: pivot needs three of its columns, got '{spec}'")
    key, across, value = parts
    keys, tops, cells = [], [], {}
    for r in rows:
        if r[key] not in keys:
            keys.append(r[key])
        if r[across] not in tops:
            tops.append(r[across])
        cells[(r[key], r[across])] = r[value]
    out = [{key: k, **{t: cells.get((k, t), "") for t in tops}} for k in keys]
    return [key] + tops, out


def render(name, options):
    meta, header, rows = read_data(name)
    if meta.get("derive") == "lookup":
        rows = derive(meta, header, rows, name)
        header = header + ["rel_mse", "frame_ms", "device"]
    if "pivot" in options:
        cols = None
    else:
        cols = options["cols"].split(",") if "cols" in options else header
    for c in cols or []:
        if c not in header:
            raise DataError(f"docs/results/{name}.csv: no column '{c}' (has {', '.join(header)})")
    if "pivot" in options:
        header, rows = pivot(name, header, rows, options["pivot"])
    if "where" in options:
        col, _, value = options["where"].partition("=")
        if col not in header:
            raise DataError(f"docs/results/{name}.csv: no column '{col}' to select on")
        rows = [r for r in rows if r[col] == value]
    if not rows:
        raise DataError(f"docs/results/{name}.csv: no rows to show")
    if cols is None:
        cols = header
    sig = int(options["sig"]) if "sig" in options else None
    titles = [c.replace("|", "\\|") for c in cols]
    lines = ["| " + " | ".join(titles) + " |", "|" + "---|" * len(cols)]
    for r in rows:
        cells = [r[c] if sig is None else round_cell(r[c], sig) for c in cols]
        lines.append("| " + " | ".join(c.replace("|", "\\|").replace("\n", " ") for c in cells) + " |")
    src = f"docs/results/{name}.csv"
    lines.append("")
    if meta.get("derive") == "lookup":
        lines.append(f"*Each row's numbers are copied from one configuration of a measured chart; `{src}` names the "
            "data file and configuration of every row.*")
        return "\n".join(lines) + "\n"
    lines.append(
        f"*Data: `{src}` ({meta['device']}; {meta['driver']}; {meta['date']}; commit {meta['commit']}). "
        f"Made by: `{meta['command']}`.*"
    )
    return "\n".join(lines) + "\n"


def parse_options(text):
    options = {}
    for part in text.split():
        key, _, value = part.partition("=")
        if key not in ("cols", "where", "sig", "pivot"):
            raise DataError(f"unknown table option '{key}'")
        options[key] = value
    return options


def markdown_files():
    yield ROOT / "README.md"
    yield from sorted((ROOT / "docs").rglob("*.md"))


def process(path):
    """(new text, names of the tables in it) of one Markdown file."""
    text = path.read_text(encoding="utf-8")
    names = []

    def replace(m):
        name, opts = m.group(1), m.group(2)
        names.append(name)
        try:
            table = render(name, parse_options(opts))
        except DataError as e:
            raise DataError(f"{path.relative_to(ROOT)}: table {name}: {e}") from None
        return f"<!-- table:{name}{opts} -->\n{table}<!-- /table -->\n"

    return MARKER.sub(replace, text), names


def main(argv):
    check = "--check" in argv[1:]
    unknown = [a for a in argv[1:] if a != "--check"]
    if unknown:
        print(f"usage: {argv[0]} [--check]", file=sys.stderr)
        return 2
    stale, count = [], 0
    try:
        for path in markdown_files():
            if not path.is_file():
                continue
            old = path.read_text(encoding="utf-8")
            if old.count("<!-- table:") != old.count("<!-- /table -->"):
                raise DataError(f"{path.relative_to(ROOT)}: a table marker is not closed")
            new, names = process(path)
            count += len(names)
            if new != old:
                stale.append(str(path.relative_to(ROOT)))
                if not check:
                    path.write_text(new, encoding="utf-8")
        for data in sorted(RESULTS.rglob("*.csv")):
            read_data(str(data.relative_to(RESULTS))[: -len(".csv")])
    except DataError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    if check and stale:
        for s in stale:
            print(f"error: {s}: a table differs from its data; run python3 tools/results_tables.py", file=sys.stderr)
        return 1
    verb = "checked" if check else ("rewrote" if stale else "unchanged")
    print(f"results_tables: {count} tables {verb}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
