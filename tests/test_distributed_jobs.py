"""The add-on's bake child pointed at a dask cluster (the Dask Scheduler preference)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from clothlight.medium_settings import BakeRequest
from tests.helpers import REPO

pytestmark = pytest.mark.slow

pytest.importorskip("distributed")


def test_the_bake_child_names_a_scheduler_that_does_not_answer_and_bakes_nothing(tmp_path):
    request = BakeRequest(preset="paper_2008").to_json()
    # stdin stays open while it runs: the worker takes its closing for a cancel
    child = subprocess.Popen([sys.executable, "-m", "clothlight.bake_worker", "--request", request, "--cache-dir",
                              str(tmp_path / "cache"), "--scheduler", "tcp://127.0.0.1:9"], cwd=REPO,
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    stdout = child.stdout.read()
    child.stdin.close()
    events = [json.loads(line) for line in stdout.splitlines()]
    assert child.wait(timeout=600) == 2 and events[-1]["event"] == "error" and events[-1]["bad_input"]
    assert "tcp://127.0.0.1:9" in events[-1]["message"]
    assert not any((tmp_path / "cache").rglob("*.exr"))
