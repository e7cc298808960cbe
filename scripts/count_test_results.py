#!/usr/bin/env python3
"""Counts test cases in JUnit XML result files (gtest, rostest, CLI tests) and prints failures.

catkin_test_results counts a rostest's gtest twice (rostest-*.xml wraps rosunit-*.xml), so we
count ourselves: rosunit-*.xml files hold the test node's cases and their rostest-*.xml wrapper
is skipped. A result file that is missing or unparsable counts as a failure.
Usage: count_test_results.py RESULT_DIR  -> prints failures, then "N passed, N failed"; exit 1 on
any failure or when no test ran.
"""
import os
import sys
import xml.etree.ElementTree as ET


def main():
    root_dir = sys.argv[1]
    passed, failed = 0, 0
    files = []
    for dirpath, _, names in os.walk(root_dir):
        files += [os.path.join(dirpath, n) for n in names if n.endswith(".xml")]
    has_rosunit = any(os.path.basename(f).startswith("rosunit-") for f in files)
    for path in sorted(files):
        base = os.path.basename(path)
        if base.startswith("rostest-") and has_rosunit:
            # The wrapper still tells when the test node never produced results.
            try:
                tree = ET.parse(path)
            except ET.ParseError:
                print("FAILED (unparsable): %s" % path)
                failed += 1
                continue
            for case in tree.iter("testcase"):
                for bad in list(case.iter("failure")) + list(case.iter("error")):
                    text = (bad.get("message") or bad.text or "")
                    if "did not generate" in text or "MISSING" in text.upper():
                        print("FAILED: %s: %s" % (base, text.strip()[:300]))
                        failed += 1
            continue
        try:
            tree = ET.parse(path)
        except ET.ParseError:
            print("FAILED (unparsable): %s" % path)
            failed += 1
            continue
        for case in tree.iter("testcase"):
            if case.get("status") == "notrun" or list(case.iter("skipped")):
                print("FAILED (skipped tests are not passes): %s %s" % (base, case.get("name")))
                failed += 1
                continue
            problems = list(case.iter("failure")) + list(case.iter("error"))
            if problems:
                failed += 1
                msg = (problems[0].get("message") or problems[0].text or "").strip()
                print("FAILED: %s: %s.%s: %s" % (base, case.get("classname"), case.get("name"),
                                                  msg[:500]))
            else:
                passed += 1
    if passed + failed == 0:
        print("no test results found in %s" % root_dir)
        failed = 1
    print("%d passed, %d failed" % (passed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
