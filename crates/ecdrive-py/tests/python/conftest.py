"""Shared set-up of the package's tests: where the `ecdrive` binary and the repository are,
and whether this run must not skip (CI)."""
import os
import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[4]
CI = os.environ.get("ECDRIVE_CI") == "1"


def binary():
    """The `ecdrive` binary the wrapper test built (ECDRIVE_BIN)."""
    path = os.environ.get("ECDRIVE_BIN")
    if not path:
        pytest.fail("ECDRIVE_BIN is not set: run these tests through `cargo test -p ecdrive-py`")
    return path


@pytest.fixture
def two_drives():
    """A master on the two emulated drives in-process, started.

    As root (CI) the cycle thread runs at SCHED_FIFO 80, as a user with root would run it:
    these tests are about the Python API, and a cycle thread at normal priority on a loaded
    two-core host stalls for milliseconds, which the emulated MR-J4-TM answers, as the drive
    does, with AL.86 (three SYNC0 cycles without outputs)."""
    import ecdrive

    priority = 80 if os.geteuid() == 0 else None
    m = ecdrive.Master("sim:mr-j4-tm,bdhde", cycle_us=1000, priority=priority)
    yield m
    m.close()
