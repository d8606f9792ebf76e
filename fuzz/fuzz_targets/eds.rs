//! The EDS/DCF reader (`EdsFile::parse`) and the lookups made on a file read.
//!
//! The checks are in `ecdrive_fuzz::eds` (`fuzz/src/lib.rs`), shared with the corpus replay of
//! the normal test suite (`tests/app/fuzz_corpus.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| ecdrive_fuzz::eds(data));
