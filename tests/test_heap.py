"""The C heap of uvsim's own processes keeps freed memory (uvsim.heap): set where glibc runs, left
alone where the user tunes malloc, and in effect in the worker processes that linearize."""
from __future__ import annotations

import os
import platform
import subprocess
import sys

import pytest

from uvsim import heap
from uvsim.fitting.worker_pool import WorkerPool

glibc = sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc"


def _clean_env(**extra):
    env = {k: v for k, v in os.environ.items() if not (k.startswith("MALLOC_") or k == "GLIBC_TUNABLES")}
    env.update(extra)
    return env


def _call(env) -> str:
    code = "from uvsim import heap; print(heap.keep_freed_memory(), heap.keep_freed_memory())"
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout.split()


def test_set_once_where_glibc_runs():
    assert _call(_clean_env()) == ([str(glibc)] * 2)


@pytest.mark.parametrize("var", ["MALLOC_TOP_PAD_", "MALLOC_ARENA_MAX", "GLIBC_TUNABLES"])
def test_left_alone_when_the_user_tunes_malloc(var):
    value = "glibc.malloc.trim_threshold=1000000" if var == "GLIBC_TUNABLES" else "1000000"
    assert _call(_clean_env(**{var: value})) == ["False", "False"]


def _heap_state(shared, item):
    return heap._done


@pytest.mark.skipif(not glibc, reason="glibc only")
def test_the_workers_set_it(monkeypatch):
    if heap._user_tuned():
        pytest.skip("this environment tunes malloc itself")
    monkeypatch.setattr(heap, "_done", None)  # not set here: the workers set it themselves
    with WorkerPool(2) as pool:
        got, _ = pool.map(_heap_state, None, [0, 1])
    assert got == [True, True] and heap._done is None
