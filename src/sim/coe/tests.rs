//! Unit tests of the CoE server internals.
