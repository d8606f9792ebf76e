//! The slave's CoE server and the master's mailbox/CoE views on arbitrary mailboxes.
//!
//! The input format and the checks are in `ecdrive_fuzz::coe` (`fuzz/src/lib.rs`), shared with
//! the corpus replay of the normal test suite (`tests/app/fuzz_corpus.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| ecdrive_fuzz::coe(data));
