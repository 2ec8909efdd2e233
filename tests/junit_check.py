#!/usr/bin/env python3
"""A JUnit consumer for `springy check --junit`: parses the file with xml.etree and checks the
elements and attributes the JUnit schema (Ant's JUnit.xsd, what Jenkins and GitLab read) requires,
that the counts add up, and what the caller expects.

usage: junit_check.py FILE --tests N --failures N --errors N [--failure-message TEXT]
Exits 1 with the reason when anything is wrong.
"""
import argparse
import sys
import xml.etree.ElementTree as ET

# Ant's JUnit.xsd: the required attributes of each element.
SUITE_ATTRIBUTES = ["name", "tests", "failures", "errors", "time", "timestamp", "hostname", "id", "package"]
CASE_ATTRIBUTES = ["name", "classname", "time"]
FAILURE_ATTRIBUTES = ["message", "type"]


def fail(why):
    print("junit_check: " + why, file=sys.stderr)
    sys.exit(1)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("file")
    parser.add_argument("--tests", type=int, required=True)
    parser.add_argument("--failures", type=int, required=True)
    parser.add_argument("--errors", type=int, required=True)
    parser.add_argument("--failure-message")
    args = parser.parse_args()

    root = ET.parse(args.file).getroot()
    if root.tag != "testsuites":
        fail("the root is <%s>, not <testsuites>" % root.tag)
    suites = root.findall("testsuite")
    if not suites:
        fail("no <testsuite>")
    tests = failures = errors = 0
    messages = []
    for suite in suites:
        for a in SUITE_ATTRIBUTES:
            if a not in suite.attrib:
                fail("<testsuite> without '%s'" % a)
        float(suite.get("time"))
        cases = suite.findall("testcase")
        if not cases:
            fail("<testsuite %s> has no <testcase>" % suite.get("name"))
        if suite.find("system-out") is None or suite.find("system-err") is None:
            fail("<testsuite %s> lacks <system-out> or <system-err>" % suite.get("name"))
        suite_failures = suite_errors = 0
        for case in cases:
            for a in CASE_ATTRIBUTES:
                if a not in case.attrib:
                    fail("<testcase> without '%s'" % a)
            float(case.get("time"))
            for kind in ("failure", "error"):
                for f in case.findall(kind):
                    for a in FAILURE_ATTRIBUTES:
                        if a not in f.attrib:
                            fail("<%s> without '%s'" % (kind, a))
                    if kind == "failure":
                        suite_failures += 1
                        messages.append(f.get("message"))
                    else:
                        suite_errors += 1
        if int(suite.get("tests")) != len(cases):
            fail("<testsuite %s> says tests=%s, has %d" % (suite.get("name"), suite.get("tests"), len(cases)))
        if int(suite.get("failures")) != suite_failures or int(suite.get("errors")) != suite_errors:
            fail("<testsuite %s>: failures/errors attributes do not match its test cases" % suite.get("name"))
        tests += len(cases)
        failures += suite_failures
        errors += suite_errors
    for name, value in (("tests", tests), ("failures", failures), ("errors", errors)):
        if int(root.get(name, -1)) != value:
            fail("<testsuites %s=%s>, but its suites have %d" % (name, root.get(name), value))
    if (tests, failures, errors) != (args.tests, args.failures, args.errors):
        fail("tests/failures/errors %d/%d/%d, expected %d/%d/%d"
             % (tests, failures, errors, args.tests, args.failures, args.errors))
    if args.failure_message is not None and args.failure_message not in messages:
        fail("no failure with the message %r (messages: %r)" % (args.failure_message, messages))
    print("junit_check: %s: %d tests, %d failures, %d errors" % (args.file, tests, failures, errors))


main()
