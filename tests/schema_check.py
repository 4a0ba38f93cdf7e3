#!/usr/bin/env python3
"""Validates every shipped case file against the JSON Schema printed by `stickslip schema`,
and checks that the schema rejects a case with an unknown key and one with a wrong type
(so that the check can fail). Exit status 1 on any failure.

Usage: python3 tests/schema_check.py PATH/TO/stickslip
"""
import glob
import json
import os
import subprocess
import sys

import jsonschema


def main() -> int:
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    here = os.path.dirname(os.path.abspath(__file__))
    schema = json.loads(subprocess.run([sys.argv[1], "schema"], check=True, capture_output=True, text=True).stdout)
    validator = jsonschema.Draft202012Validator(schema)
    cases = sorted(glob.glob(os.path.join(here, "..", "cases", "*.json")))
    if not cases:
        print("schema_check: no case files found")
        return 1
    failed = 0
    for path in cases:
        errors = list(validator.iter_errors(json.load(open(path))))
        name = os.path.relpath(path, os.path.join(here, ".."))
        if errors:
            failed += 1
            print(f"schema_check: {name}: {errors[0].message} at {list(errors[0].absolute_path)}")
        else:
            print(f"schema_check: {name}: valid")
    base = json.load(open(cases[0]))
    bad_key = dict(base, stpes=[])
    bad_type = dict(base, bodies="lower_body")
    for label, bad in [("unknown key", bad_key), ("wrong type", bad_type)]:
        if validator.is_valid(bad):
            failed += 1
            print(f"schema_check: the schema accepted a case with a {label}")
        else:
            print(f"schema_check: a case with a {label} is rejected")
    print(f"schema_check: {'all pass' if failed == 0 else f'{failed} failure(s)'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
