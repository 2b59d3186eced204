"""Paths the tests share: the tests folder and the repository root."""

from pathlib import Path

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
