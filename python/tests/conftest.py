"""Shared fixtures: the `tdcr` command built by `cargo build --release` (or `cargo test
--release`) at the repository root, to compare against the Rust side."""

import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _binary() -> pathlib.Path:
    path = pathlib.Path(os.environ.get("TDCR_BIN", ROOT / "target" / "release" / "tdcr"))
    if not path.exists():
        pytest.fail(f"{path} is missing: run `cargo build --release` at the repository root (or set TDCR_BIN)")
    return path


@pytest.fixture(scope="session")
def cli():
    """Runs `tdcr ARGS` with `stdin`; returns the parsed JSON of standard output."""
    binary = _binary()

    def run(args, stdin=None):
        out = subprocess.run([str(binary), *args], input=stdin, capture_output=True, text=True, check=True)
        return json.loads(out.stdout)

    return run


@pytest.fixture(scope="session")
def cli_text():
    """Runs `tdcr ARGS` with `stdin` in `cwd`; returns standard output as text."""
    binary = _binary()

    def run(args, stdin=None, cwd=None):
        out = subprocess.run([str(binary), *args], input=stdin, capture_output=True, text=True, check=True, cwd=cwd)
        return out.stdout

    return run
