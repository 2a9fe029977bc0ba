#!/usr/bin/env python3
"""`incise certify --junit FILE` (docs/cli.md): the JUnit XML parses, has one <testcase> per
check run, and a <failure> exactly for the checks that failed.
Usage: certify_junit.py INCISE DATA_DIR WORK_DIR

1. Two quick checks that pass (box_volume and cylinder_volume, selected by --filter=RE: the
   --opt=value form; the checks run are read from the PASS/FAIL lines on stdout): exit 0,
   nothing on stderr (-q); <testsuites>/<testsuite> with tests = 2, failures = 0; one <testcase classname="incise.certify"> per
   check, named by its id, with a numeric time attribute >= 0; no <failure>.
2. The same run with a data folder whose box_volume band is [1, 2] (a copy of DATA_DIR's
   tolerances.json, changed in WORK_DIR): exit 3 (a check out of its band); box_volume's
   testcase holds one <failure> whose message names the quantity "not in [1, 2]"; failures = 1.
"""
import json
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

incise, data, work = sys.argv[1:4]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
FILTER = "^(box_volume|cylinder_volume)$"


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def certify(data_dir, junit):
    p = subprocess.run([incise, "certify", "-q", "--quick", f"--filter={FILTER}", "--data",
                        data_dir, "--out", os.path.join(work, "out"), "--junit", junit],
                       capture_output=True, text=True, check=False)
    print(p.stdout, p.stderr)
    lines = re.findall(r"^  (PASS|FAIL)  (\S+)", p.stdout, re.M)
    return p.returncode, p.stderr, lines, ET.parse(junit).getroot()


def check_structure(root, lines):
    if root.tag != "testsuites":
        fail(f"root element {root.tag}, expected testsuites")
    suites = root.findall("testsuite")
    if len(suites) != 1:
        fail(f"{len(suites)} testsuite elements, expected 1")
    suite = suites[0]
    cases = suite.findall("testcase")
    if [c.get("name") for c in cases] != [name for _, name in lines]:
        fail(f"testcases {[c.get('name') for c in cases]} != checks run {lines}")
    if int(suite.get("tests")) != len(lines) or int(root.get("tests")) != len(lines):
        fail(f"tests attribute {suite.get('tests')} != {len(lines)} checks")
    failed = sum(1 for verdict, _ in lines if verdict == "FAIL")
    if int(suite.get("failures")) != failed or int(root.get("failures")) != failed:
        fail(f"failures attribute {suite.get('failures')} != {failed}")
    for c in cases:
        if c.get("classname") != "incise.certify" or float(c.get("time")) < 0:
            fail(f"testcase attributes {c.attrib}")
    float(suite.get("time"))
    return {c.get("name"): c for c in cases}


# 1. Passing checks.
rc, err, lines, root = certify(data, os.path.join(work, "pass.xml"))
if rc != 0 or err != "" or len(lines) != 2:
    fail(f"exit {rc} (expected 0), stderr {err!r}, {len(lines)} checks (expected 2)")
cases = check_structure(root, lines)
if any(c.find("failure") is not None for c in cases.values()):
    fail("a <failure> in a run where every check passed")

# 2. box_volume forced out of its band.
tightened = os.path.join(work, "data")
os.makedirs(os.path.join(tightened, "certify"))
with open(os.path.join(data, "certify", "tolerances.json")) as f:
    tolerances = json.load(f)
tolerances["checks"]["box_volume"]["relative"]["band"] = [1, 2]
with open(os.path.join(tightened, "certify", "tolerances.json"), "w") as f:
    json.dump(tolerances, f)
for sub in os.listdir(data):  # the rest of the data folder (meshes, ...) as links
    if sub != "certify":
        os.symlink(os.path.join(os.path.abspath(data), sub), os.path.join(tightened, sub))
rc, err, lines, root = certify(tightened, os.path.join(work, "fail.xml"))
if rc != 3:
    fail(f"exit {rc}, expected 3 (a check out of its band)")
cases = check_structure(root, lines)
failures = cases["box_volume"].findall("failure")
if len(failures) != 1 or "not in [1, 2]" not in failures[0].get("message"):
    fail(f"box_volume failures {[f.attrib for f in failures]}")
if cases["cylinder_volume"].find("failure") is not None:
    fail("cylinder_volume passed but has a <failure>")
print("certify --junit: ok (one testcase per check, failure exactly where a check failed)")
