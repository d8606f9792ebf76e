//! Values between Rust and Python: JSON documents as plain dicts and lists, SDO values typed by
//! the object's data type.

use crate::errors::Failure;
use ecdrive::od::{DataType, Value};
use pyo3::IntoPyObjectExt;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use std::time::Duration;

/// A JSON document as Python objects (dict, list, str, int, float, bool, None).
pub fn json_to_py(py: Python<'_>, v: &serde_json::Value) -> PyResult<Py<PyAny>> {
    Ok(match v {
        serde_json::Value::Null => py.None(),
        serde_json::Value::Bool(b) => b.into_py_any(py)?,
        serde_json::Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_py_any(py)?
            } else if let Some(u) = n.as_u64() {
                u.into_py_any(py)?
            } else {
                n.as_f64().unwrap_or(f64::NAN).into_py_any(py)?
            }
        }
        serde_json::Value::String(s) => s.into_py_any(py)?,
        serde_json::Value::Array(a) => {
            let items = a
                .iter()
                .map(|x| json_to_py(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any().unbind()
        }
        serde_json::Value::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any().unbind()
        }
    })
}

/// Anything serializable as Python objects, through its JSON form (the CLI's `--json`).
pub fn to_py<T: serde::Serialize>(py: Python<'_>, what: &str, v: &T) -> PyResult<Py<PyAny>> {
    let j = serde_json::to_value(v)
        .map_err(|e| Failure::config(format!("converting {what} to Python"), e))?;
    json_to_py(py, &j)
}

/// Seconds as a duration: finite and not negative.
pub fn seconds(s: f64) -> PyResult<Duration> {
    if (0.0..1e9).contains(&s) {
        Ok(Duration::from_secs_f64(s))
    } else {
        Err(Failure::config(
            "reading a time in seconds",
            format!("{s} is not a duration"),
        )
        .into())
    }
}

/// A data type by the CLI's names (`u32`, `i16`, `UNSIGNED32`, `string`, …).
pub fn data_type(name: &str) -> PyResult<DataType> {
    DataType::parse(name).ok_or_else(|| {
        Failure::config(
            format!("reading the data type {name:?}"),
            "not a data type (u8, u16, u32, u64, i8, i16, i32, i64, f32, f64, bool, string, \
             octets, or the CiA 301 names)",
        )
        .into()
    })
}

/// An uploaded value as Python: int, float, str or bytes by its data type; the bytes as they
/// came when the type is not known.
pub fn sdo_to_py(py: Python<'_>, dt: Option<DataType>, bytes: &[u8]) -> PyResult<Py<PyAny>> {
    let Some(dt) = dt else {
        return Ok(PyBytes::new(py, bytes).into_any().unbind());
    };
    let v = Value::decode(dt, bytes).map_err(|e| {
        Failure::config(
            format!("decoding the value as {dt}"),
            format!("{e}; the device sent {} byte(s)", bytes.len()),
        )
    })?;
    match v {
        Value::Int(i) => i.into_py_any(py),
        Value::Uint(u) => u.into_py_any(py),
        Value::Real(r) => r.into_py_any(py),
        Value::Str(s) => s.into_py_any(py),
        Value::Bytes(b) => Ok(PyBytes::new(py, &b).into_any().unbind()),
    }
}

/// A Python value to write as `dt` (an int, float, str or bytes); bytes are written as they
/// are whatever the type.
pub fn py_to_sdo(v: &Bound<'_, PyAny>, dt: Option<DataType>) -> PyResult<Vec<u8>> {
    if let Ok(b) = v.cast::<PyBytes>() {
        return Ok(b.as_bytes().to_vec());
    }
    let Some(dt) = dt else {
        return Err(Failure::config(
            "encoding the value",
            "the object's data type is not known (not in the drive's dictionary): pass \
             type=\"u32\" (or the right one), or the value as bytes",
        )
        .into());
    };
    let value = if let Ok(i) = v.extract::<i64>() {
        if i >= 0 {
            Value::Uint(i as u64)
        } else {
            Value::Int(i)
        }
    } else if let Ok(u) = v.extract::<u64>() {
        Value::Uint(u)
    } else if let Ok(f) = v.extract::<f64>() {
        Value::Real(f)
    } else if let Ok(s) = v.extract::<String>() {
        Value::Str(s)
    } else {
        return Err(Failure::config(
            "encoding the value",
            "expected an int, a float, a str or bytes",
        )
        .into());
    };
    value
        .encode(dt)
        .map_err(|e| Failure::config(format!("encoding the value as {dt}"), e).into())
}
