//! The ESI parser (`EsiFile::parse_bytes`) and everything derived from a parsed file.
//!
//! The input format and the checks are in `ecdrive_fuzz::esi` (`fuzz/src/lib.rs`), shared with
//! the corpus replay of the normal test suite (`tests/app/fuzz_corpus.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| ecdrive_fuzz::esi(data));
