"""Shared fixtures of the Python module's tests (run by ctest: tests/CMakeLists.txt sets
PYTHONPATH to the build tree's python/ and SPRINGY_BINARY to the springy program)."""
import os
import subprocess

import pytest

SOURCE = os.environ.get("SPRINGY_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
SCENES = os.path.join(SOURCE, "scenes")


def scene(name):
    return os.path.join(SCENES, name + ".toml")


@pytest.fixture
def springy_cli():
    """Runs the springy program; returns the completed process (check=True: a failure raises)."""
    binary = os.environ.get("SPRINGY_BINARY")
    if not binary:
        pytest.skip("SPRINGY_BINARY is not set (ctest sets it)")

    def run(*args, check=True):
        return subprocess.run([binary, *map(str, args)], capture_output=True, text=True, check=check)

    return run
