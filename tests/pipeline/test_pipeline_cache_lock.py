"""Content-hash task cache and the output-folder lock."""

import json
import os
import subprocess
import sys
import textwrap

import pytest

from fivid.pipeline.cache import Task, TaskCache, digest, file_sha256
from fivid.execution.lock import LockedError, OutputLock


def test_file_sha256_matches_hashlib_on_multi_chunk_file(tmp_path):
    import hashlib

    data = os.urandom(3 * (1 << 20) + 17)  # crosses the 1 MiB read-chunk boundary
    p = tmp_path / "f.bin"
    p.write_bytes(data)
    assert file_sha256(p) == hashlib.sha256(data).hexdigest()


def test_digest_is_canonical():
    import numpy as np

    assert digest({"a": 1, "b": [1.5, 2.0]}) == digest({"b": [1.5, np.float64(2.0)], "a": np.int64(1)})
    assert digest({"a": 1}) != digest({"a": 2})


def _task(tmp_path, params=None, inputs=None):
    return Task("stage", "t1", params or {"x": 1}, inputs or {"in": "abc"}, {"out": str(tmp_path / "o.txt")})


def test_cache_hit_only_for_same_key_and_intact_outputs(tmp_path):
    cache = TaskCache(tmp_path)
    task = _task(tmp_path)
    assert cache.lookup(task) is None
    (tmp_path / "o.txt").write_text("result")
    rec = cache.record(task, seconds=0.1)
    assert cache.lookup(task) == rec == {"out": file_sha256(tmp_path / "o.txt")}
    assert cache.lookup(_task(tmp_path, params={"x": 2})) is None       # parameters changed
    assert cache.lookup(_task(tmp_path, inputs={"in": "abd"})) is None   # an input changed
    (tmp_path / "o.txt").write_text("resulT")                             # output damaged, same size
    assert cache.lookup(task) is None
    (tmp_path / "o.txt").unlink()
    assert cache.lookup(task) is None


_HOLDER = textwrap.dedent("""
    import sys, time
    from fivid.execution.lock import OutputLock
    lock = OutputLock(sys.argv[1]).acquire()
    print("locked", flush=True)
    time.sleep(60)
""")


def _start_holder(folder):
    proc = subprocess.Popen([sys.executable, "-c", _HOLDER, str(folder)], stdout=subprocess.PIPE, text=True,
                            cwd=os.getcwd())
    assert proc.stdout.readline().strip() == "locked"
    return proc


def test_second_run_is_refused_while_first_holds_the_lock(tmp_path):
    proc = _start_holder(tmp_path)
    try:
        with pytest.raises(LockedError) as err:
            OutputLock(tmp_path).acquire()
        assert f"pid {proc.pid}" in str(err.value) and "in use by another fivid run" in str(err.value)
    finally:
        proc.kill()
        proc.wait()


def test_lock_of_a_killed_run_is_taken_over_and_reported(tmp_path, caplog):
    proc = _start_holder(tmp_path)
    proc.kill()  # SIGKILL: the lock file stays, the kernel drops the flock
    proc.wait()
    assert (tmp_path / ".fivid-run.lock").exists()
    with caplog.at_level("WARNING", logger="fivid"):
        with OutputLock(tmp_path) as lock:
            assert lock.took_over["pid"] == proc.pid
            assert json.loads((tmp_path / ".fivid-run.lock").read_text())["pid"] == os.getpid()
    assert f"pid {proc.pid}" in caplog.text and "took over a stale lock" in caplog.text
    assert not (tmp_path / ".fivid-run.lock").exists()


def test_lock_from_another_host_is_refused_with_advice(tmp_path):
    (tmp_path / ".fivid-run.lock").write_text(json.dumps({"pid": 1, "hostname": "elsewhere", "started": "x"}))
    with pytest.raises(LockedError) as err:
        OutputLock(tmp_path).acquire()
    assert "elsewhere" in str(err.value) and "delete" in str(err.value)
