#!/usr/bin/env python3
"""`incise mesh check --json` (docs/cli.md): the JSON on stdout parses and holds what the text
report prints. Usage: mesh_check_json.py INCISE LIVER_MESH BAD_MESH

1. The shipped liver: exit 0; stdout is one JSON document (nothing else); counts, loader and
   validation equal the numbers of the text report of the same file; every quality statistic
   has min <= p05 <= median <= p95 <= max; valid is true, no violations.
2. The liver with --keep-pinched: exit 1 (bad input: invalid mesh), valid false, the first
   violation is the [connected-star] the text mode names on stderr.
3. A malformed file: exit 1, nothing on stdout, "file:line:" on stderr.
"""
import json
import re
import subprocess
import sys

incise, liver, bad = sys.argv[1:4]


def run(*args):
    p = subprocess.run([incise, *args], capture_output=True, text=True, check=False)
    return p.returncode, p.stdout, p.stderr


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


# 1. --json (and --scale=VALUE: the --opt=value form) against the text report.
rc, out, err = run("mesh", "check", liver, "--json", "--scale=1")
if rc != 0:
    fail(f"exit {rc}, expected 0; stderr {err!r}")
doc = json.loads(out)  # raises (test fails) unless stdout is exactly one JSON document
rc_t, text, _ = run("mesh", "check", liver)
m = re.search(r"counts: +(\d+) vertices, (\d+) tetrahedra, (\d+) boundary triangles", text)
if not m:
    fail("text report has no counts line")
expected_counts = {"vertices": int(m[1]), "cells": int(m[2]),
                   "boundary_triangles_in_file": int(m[3]), "cell_kind": "tetrahedra"}
if doc["counts"] != expected_counts:
    fail(f"counts {doc['counts']} != text report {expected_counts}")
m = re.search(r"connectivity: (\d+) elements, (\d+) faces, (\d+) boundary faces", text)
if doc["connectivity"] != {"elements": int(m[1]), "faces": int(m[2]),
                           "boundary_faces": int(m[3])}:
    fail(f"connectivity {doc['connectivity']} != text report {m[0]}")
m = re.search(r"loader: +(\d+) reoriented, (\d+) duplicate vertices \((\d+) merged\), (\d+) unused "
              r"vertices, (\d+) pinched vertices split, (\d+) ignored records", text)
loader = doc["loader"]
got = [loader[k] for k in ("reoriented", "duplicate_vertices", "merged_vertices",
                           "unused_vertices", "pinched_vertices_split", "ignored_records")]
if got != [int(x) for x in m.groups()]:
    fail(f"loader {got} != text report {m.groups()}")
if doc["valid"] is not True or doc["violations"] != [] or "validation:  ok" not in text:
    fail(f"valid {doc['valid']}, violations {doc['violations'][:2]}")
for name in ("volume", "aspect_ratio", "shewchuk", "min_dihedral_deg", "max_dihedral_deg",
             "edge_length"):
    s = doc["quality"][name]
    if not s["min"] <= s["p05"] <= s["median"] <= s["p95"] <= s["max"]:
        fail(f"quality.{name} not ordered: {s}")
if sum(doc["quality"]["shapes"].values()) != doc["counts"]["cells"]:
    fail(f"shape counts {doc['quality']['shapes']} do not add up to the cells")
if doc["format"] != "medit 1" or doc["dimension"] != 3 or doc["scale"] != 1:
    fail(f"format/dimension/scale: {doc['format']}, {doc['dimension']}, {doc['scale']}")

# 2. An invalid mesh: exit 1, valid false, the violation named.
rc, out, err = run("mesh", "check", liver, "--keep-pinched", "--json")
doc = json.loads(out)
if rc != 1 or doc["valid"] is not False or not doc["violations"]:
    fail(f"--keep-pinched: exit {rc}, valid {doc['valid']}, {len(doc['violations'])} violations")
if doc["violations"][0]["invariant"] != "connected-star" or "[connected-star]" not in err:
    fail(f"first violation {doc['violations'][0]}, stderr {err!r}")

# 3. Unreadable: exit 1, stdout empty, the file and line on stderr.
rc, out, err = run("mesh", "check", bad, "--json")
if rc != 1 or out != "" or not re.search(r"bad_index\.mesh:11: ", err):
    fail(f"bad file: exit {rc}, stdout {out[:80]!r}, stderr {err!r}")
print("mesh check --json: ok (counts, loader, connectivity, validity equal the text report)")
