"""Shared fixtures: the repository's root and the command-line tool to compare with."""

import os
import pathlib
import shutil

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _cli():
    """The `eigenray` binary: $EIGENRAY_BIN, else one built in this checkout."""
    given = os.environ.get("EIGENRAY_BIN")
    if given:
        return given
    for profile in ("release", "test-opt", "debug"):
        candidate = ROOT / "target" / profile / "eigenray"
        if candidate.exists():
            return str(candidate)
    found = shutil.which("eigenray")
    if found:
        return found
    raise RuntimeError(
        "no eigenray binary: run `cargo build --release` in the repository "
        "or set EIGENRAY_BIN"
    )


@pytest.fixture(scope="session")
def cli():
    return _cli()


@pytest.fixture(scope="session")
def root():
    return ROOT
