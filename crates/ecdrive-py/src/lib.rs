//! ecdrive for Python: the extension module `ecdrive._ecdrive`, wrapped by the package
//! `ecdrive` (`python/ecdrive`).
//!
//! The master's cycle runs in ecdrive's own thread, as it does for a Rust application; Python
//! is never called from it. Every call that waits (start-up, an SDO, enabling, homing, a move)
//! releases the GIL while it waits, so other Python threads run on. Errors are Python
//! exceptions of one class per kind, carrying what the Rust error carries.

use pyo3::prelude::*;

mod audit;
mod backend;
mod canopen;
mod devices;
mod errors;
mod master;
mod record;
mod values;

pub use errors::{BusError, ConfigError, DriveFault, DriveRefused, Error};

/// The extension's allocator: the system's, counting the allocations of a thread inside an
/// open window (the cycle audit, `Master(..., audit=True)`); outside a window it only checks a
/// thread-local flag.
#[global_allocator]
static ALLOC: ecdrive::rt::audit::CountingAlloc = ecdrive::rt::audit::CountingAlloc;

/// Run a run file (`ecdrive run FILE`) to its end and return the run's JSON summary (what
/// `ecdrive run --json` prints) as a dict. EtherCAT and CANopen run files alike; `interface`
/// overrides the file's target as `--interface` does, `duration` (seconds) its duration.
#[pyfunction]
#[pyo3(signature = (path, *, interface=None, duration=None))]
fn run(
    py: Python<'_>,
    path: std::path::PathBuf,
    interface: Option<String>,
    duration: Option<f64>,
) -> PyResult<Py<PyAny>> {
    let duration = duration.map(values::seconds).transpose()?;
    let summary = py.detach(move || master::run_file(&path, interface.as_deref(), duration))?;
    values::json_to_py(py, &summary)
}

/// The extension module.
#[pymodule]
fn _ecdrive(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<Error>())?;
    m.add("ConfigError", py.get_type::<ConfigError>())?;
    m.add("BusError", py.get_type::<BusError>())?;
    m.add("DriveRefused", py.get_type::<DriveRefused>())?;
    m.add("DriveFault", py.get_type::<DriveFault>())?;
    m.add_class::<master::Master>()?;
    m.add_class::<master::Drive>()?;
    m.add_class::<devices::Device>()?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
