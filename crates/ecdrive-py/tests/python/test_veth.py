"""The package over a real raw socket: the master on one end of a veth pair, `ecdrive sim`
serving the two emulated drives on the other end, in a network namespace. The wrapper test
(tests/wheel.rs) creates them and passes the interfaces: ECDRIVE_PY_VETH (the drives, served
already) and ECDRIVE_PY_VETH_ALARM (a pair whose sim the fault test starts itself, with the
BDHDE's alarm J3 to come). Under ECDRIVE_CI they must be there: CI runs as root and never skips
these."""
import os
import subprocess

import pytest

import ecdrive
from conftest import CI, binary

VETH = os.environ.get("ECDRIVE_PY_VETH")
ALARM = os.environ.get("ECDRIVE_PY_VETH_ALARM")


def need(iface):
    if iface:
        return iface
    if CI:
        pytest.fail("ECDRIVE_CI is set but no veth interface was passed (the wrapper runs as root)")
    pytest.skip("no veth interface (run as root through `cargo test -p ecdrive-py`)")


def test_two_drives_over_veth():
    iface = need(VETH)
    m = ecdrive.Master(iface, start=False)
    try:
        slaves = m.slaves()
        assert [(s["position"], s["vendor_id"], s["product_code"]) for s in slaves] == [
            (0, 0x00000A1E, 0x00000201),
            (1, 0x000002E1, 0x000BE2EB),
        ]
        m.start()
        assert [d.state for d in m.devices] == ["OP", "OP"]
        drives = m.drives
        assert drives[0].sdo_read(0x1018, 1) == 0x00000A1E
        for ax in drives:
            ax.enable()
        drives[1].home(method=35)
        assert drives[1].position == 0
        for ax in drives:
            ax.move_by(100000, velocity=500000, acceleration=5000000, wait=False)
        for ax in drives:
            ax.wait()
            assert ax.state == "Operation enabled"
        assert abs(drives[1].position - 100000) <= 2
        cols = m.record()
        assert len(cols["cycle"]) > 200
        assert m.max_wake_latency_us > 0
        summary = m.stop()
        assert summary["shutdown_ok"] is True
        assert summary["cycle"]["cycles"] > 200
    finally:
        m.close()


def sim_with_alarm(at):
    """`ecdrive sim` on the alarm pair's peer end: the BDHDE (position 1) raises J3 at `at`."""
    netns = os.environ["ECDRIVE_PY_ALARM_NETNS"]
    peer = os.environ["ECDRIVE_PY_ALARM_PEER"]
    p = subprocess.Popen(
        ["ip", "netns", "exec", netns, binary(), "sim", "--interface", peer,
         "--sm-watchdog", "0", "--device", "mr-j4-tm", "--device", "bdhde",
         "--alarm", f"1:J3@{at}"],
        stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
    )
    banner = ""
    for line in p.stderr:
        banner += line
        if line.startswith("  1: "):
            break
    assert "serving 2 device(s)" in banner, banner
    return p


def test_a_drive_fault_raises_drivefault_and_leaves_no_drive_enabled():
    iface = need(ALARM)
    sim = sim_with_alarm("3s")
    m = None
    try:
        m = ecdrive.Master(iface)
        drives = m.drives
        # Whenever the alarm comes (while enabling, or during the moves), it is a DriveFault
        # naming the drive and the manual's alarm.
        with pytest.raises(ecdrive.DriveFault) as e:
            for ax in drives:
                ax.enable()
            for _ in range(100):
                drives[0].move_by(400000, velocity=200000, acceleration=2000000, timeout=30.0)
                drives[0].move_by(-400000, velocity=200000, acceleration=2000000, timeout=30.0)
        assert "J3" in str(e.value), str(e.value)
        assert e.value.drive in ("BDHDE", "MR-J4-TM")
        # Every axis stopped and disabled: none is left enabled.
        if m.running:
            assert "Operation enabled" not in [ax.state for ax in drives]
        summary = m.stop()
        for d in summary["drives"]:
            assert d["states"][-1] != "Operation enabled", d
    finally:
        if m is not None:
            m.close()
        sim.terminate()
        sim.wait()
