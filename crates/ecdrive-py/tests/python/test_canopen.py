"""The CANopen drives through the same classes: a CANopen run file's drives (the Oriental
BLV-R, the Schneider Lexium MDrive and the Delta ASDA-A2, emulated in-process: `can-sim`)
started by `ecdrive.Master`, driven by the same `Drive` objects. Identities are the manuals':
BLV-R vendor 0x000002BE product 0x000013F7, ASDA-A2 vendor 0x000001DD product 0x00006000,
Lexium MDrive vendor 0x0000021B."""
import pytest

import ecdrive
from conftest import REPO

FILE = str(REPO / "examples" / "canopen_profile_modes.toml")


def test_canopen_drives_through_the_same_classes():
    m = ecdrive.Master(FILE)
    try:
        devices = m.devices
        assert [(d.position, d.name, d.state) for d in devices] == [
            (3, "BLV-R", "OPERATIONAL"),
            (65, "Lexium MDrive", "OPERATIONAL"),
            (127, "ASDA-A2", "OPERATIONAL"),
        ]
        assert [(d.vendor_id, d.product_code) for d in devices] == [
            (0x000002BE, 0x000013F7),
            (0x0000021B, 0x00000000),
            (0x000001DD, 0x00006000),
        ]
        assert [ax.mode for ax in m.drives] == ["pp", "pp", "pp"]
        for ax in m.drives:
            ax.enable()
            assert ax.state == "Operation enabled"
        blv = m.drive("BLV-R")
        blv.move_to(36000)  # pp: one revolution of the BLV-R (36 000 counts)
        assert blv.position == 36000
        blv.move_by(-18000)
        assert blv.position == 18000
        with pytest.raises(ecdrive.ConfigError, match="runs pp"):
            blv.move_to(0, velocity=1000, acceleration=1000)
        with pytest.raises(ecdrive.BusError, match="cycle thread owns the bus"):
            blv.sdo_read(0x1018, 1)
        with pytest.raises(ecdrive.ConfigError, match="record"):
            m.record()
        with pytest.raises(ecdrive.ConfigError, match="EtherCAT"):
            m.slaves()
        # The Lexium's program from the file: home, pp to 1 and 0.5 rev, pv 5 rev/s for 0.2 s.
        lexium = m.drive(65)
        lexium.run_program(timeout=60.0)
        assert lexium.mode == "pp"
        assert abs(lexium.position - int(1.5 * 51200)) <= 512, lexium.position
        blv.mode = "pv"
        assert blv.mode == "pv"
        texts = [h["text"] for h in m.history()]
        assert "program done" in texts and "mode pp (1) → pv (3)" in texts
        summary = m.stop()
        assert summary["shutdown_ok"] is True
        assert [d["state"] for d in summary["drives"]] == ["Switch on disabled"] * 3
        assert not m.running
    finally:
        m.close()


def test_a_canopen_run_file_runs_to_its_end():
    summary = ecdrive.run(FILE)
    assert summary["outcome"] == "completed", summary.get("reason")
