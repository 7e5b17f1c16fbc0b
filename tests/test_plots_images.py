"""The pictures the documentation shows are kept in git (``tests/test_docs.py`` checks that they exist, are PNG and
that ``docs/make_images.py`` draws each)."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from tests.test_docs import PAGES, ROOT, images


def test_every_image_shown_is_in_git():
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    shown = sorted({p.relative_to(ROOT).as_posix() for page in PAGES for p in images(page)})
    assert shown
    tracked = subprocess.run(
        ["git", "ls-files", "--", *shown], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    missing = sorted(set(shown) - set(tracked))
    assert not missing, f"shown by the docs but not in git (git add them): {missing}"
