#!/usr/bin/env python3
"""Totals the JUnit XML results of gtest, pytest and rostest under a results
directory and prints one closing line "N passed, N failed, N skipped".

A test program that exited non-zero without reporting a failure (a crash, a
timeout, a rostest whose test node never ran) counts as one failed test.
Exit status: 0 only if nothing failed and at least one test ran."""
import glob
import os
import sys
import xml.etree.ElementTree as ET


def count_cases(path):
    """(passed, failed, skipped, names of failures) of one JUnit XML file."""
    passed = failed = skipped = 0
    failures = []
    root = ET.parse(path).getroot()
    for case in root.iter("testcase"):
        name = "%s.%s" % (case.get("classname", ""), case.get("name", ""))
        if case.find("failure") is not None or case.find("error") is not None:
            failed += 1
            failures.append(name)
        elif case.find("skipped") is not None or case.get("status") == "notrun":
            skipped += 1
        else:
            passed += 1
    return passed, failed, skipped, failures


def exit_codes(path):
    codes = {}
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                name, rc = line.split()
                codes[name] = int(rc)
    return codes


def main(results):
    passed = failed = skipped = 0
    failures = []

    def add(xml_files, label, rc):
        nonlocal passed, failed, skipped
        p = f = s = 0
        for x in xml_files:
            try:
                dp, df, ds, names = count_cases(x)
            except ET.ParseError as e:
                dp, df, ds, names = 0, 1, 0, ["%s (unreadable result %s: %s)" % (label, x, e)]
            p, f, s = p + dp, f + df, s + ds
            failures.extend(names)
        if rc != 0 and f == 0:
            f = 1  # crashed, timed out or never ran: count it
            failures.append("%s (exit code %d, no failing test reported)" % (label, rc))
        passed, failed, skipped = passed + p, failed + f, skipped + s

    for name, rc in sorted(exit_codes(os.path.join(results, "gtest", "exit_codes")).items()):
        add(glob.glob(os.path.join(results, "gtest", name + ".xml")), "gtest " + name, rc)
    for name, rc in sorted(exit_codes(os.path.join(results, "pytest", "exit_codes")).items()):
        add([os.path.join(results, "pytest", "pytest.xml")] if os.path.exists(
            os.path.join(results, "pytest", "pytest.xml")) else [], "pytest", rc)
    for name, rc in sorted(exit_codes(os.path.join(results, "rostest", "exit_codes")).items()):
        # rostest writes one XML per test node (rosunit-*.xml) plus its own
        # rostest-*.xml, which only repeats them.
        xmls = [x for x in glob.glob(os.path.join(results, "rostest", name, "**", "*.xml"), recursive=True)
                if not os.path.basename(x).startswith("rostest-")]
        if not xmls:
            rc = rc or 1
        add(xmls, "rostest " + name, rc)

    for name in failures:
        print("FAILED: %s" % name)
    print("%d passed, %d failed, %d skipped" % (passed, failed, skipped))
    return 0 if failed == 0 and passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
