"""ecdrive: an EtherCAT master for CiA 402 servo drives, with its real-time cycle in Rust.

    import ecdrive

    with ecdrive.Master("sim:mr-j4-tm,bdhde", cycle_us=1000) as m:
        ax = m.drive(1)
        ax.enable()
        ax.move_to(100000, velocity=500000, acceleration=5000000)
        print(ax.position, ax.following_error)

The cycle runs in ecdrive's own thread and never calls Python; every call that waits
releases the GIL. See the book's "ecdrive for Python" page.
"""

from . import _ecdrive
from ._ecdrive import (  # noqa: F401
    BusError,
    ConfigError,
    Device,
    Drive,
    DriveFault,
    DriveRefused,
    Error,
    __version__,
    run,
)

try:  # numpy is optional: record() gives arrays with it, lists without.
    import numpy as _np
except ImportError:  # depends on the environment
    _np = None


class Master(_ecdrive.Master):
    __doc__ = _ecdrive.Master.__doc__

    def record(self, *, arrays=None):
        """Every cycle's samples since the last call, as columns: one row per axis and cycle
        with a reply. numpy arrays when numpy is installed (missing values as NaN), lists
        otherwise; ``arrays=False`` always gives lists."""
        cols = super().record()
        if _np is None or arrays is False:
            return cols
        out = {}
        for name, values in cols.items():
            if any(v is None for v in values):
                out[name] = _np.array(
                    [_np.nan if v is None else v for v in values], dtype=float
                )
            else:
                out[name] = _np.asarray(values)
        return out


__all__ = [
    "BusError",
    "ConfigError",
    "Device",
    "Drive",
    "DriveFault",
    "DriveRefused",
    "Error",
    "Master",
    "run",
]
