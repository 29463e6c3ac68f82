#!/usr/bin/python3
"""The smoke fixture is as it was built (ctest `smoke_fixture_unchanged`, FIXTURES_CLEANUP
smoke_results): every file under $SIRL_SMOKE_FIXTURE hashes as MANIFEST.json lists it, none was
added or removed. A test that wrote into the shared folder instead of its copy
(sirl_testing.copy_fixture) is named by the files it changed.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_smoke_fixture  # noqa: E402
import sirl_testing  # noqa: E402

fail = sirl_testing.make_fail("smoke_fixture_unchanged")


def main():
    target = os.environ.get("SIRL_SMOKE_FIXTURE")
    if not target:
        fail("SIRL_SMOKE_FIXTURE is not set (tests/CMakeLists.txt sets it)")
    manifest = make_smoke_fixture.read_manifest(target)
    if manifest is None or not manifest.get("files"):
        fail(f"{target}/MANIFEST.json is missing or unreadable (was the fixture built?)")
    diff = make_smoke_fixture.differences(target, manifest)
    if diff:
        fail(f"a test wrote into the shared fixture {target} (tests must copy it: "
             f"sirl_testing.copy_fixture): {len(diff)} file(s): " + "; ".join(diff[:20]))
    print(f"smoke_fixture_unchanged: OK ({len(manifest['files'])} files as listed)")


if __name__ == "__main__":
    main()
