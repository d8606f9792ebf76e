//! The application's tests: the `ecdrive` command as a user runs it, the run file, the demo, soak and jitter harness, both buses end to end, the manuals' facts through the bus, and the repository's own checks (layering, docs).
//!
//! One test binary for the crate `ecdrive-cli`: each module was a test file of its own.

// The allocation audits count the allocations a thread makes inside its window.
#[global_allocator]
static ALLOC: ecdrive::rt::audit::CountingAlloc = ecdrive::rt::audit::CountingAlloc;

mod canopen_util;
mod support;

// The fuzz targets' checks, run here on their corpora and on generated inputs.
#[path = "../../fuzz/src/lib.rs"]
mod fuzz_checks;

mod canopen_alloc;
mod canopen_crossprocess;
mod canopen_cycle_audit;
mod canopen_demo;
mod canopen_drives;
mod canopen_emcy;
mod canopen_fuzz;
mod canopen_machine;
mod canopen_motion;
mod canopen_nmt;
mod canopen_pdo;
mod canopen_reset;
mod canopen_run;
mod canopen_sdo;
mod canopen_sim_cli;
mod check_catches;
mod cli_bus;
mod cli_config;
mod cli_diag;
mod cli_errors;
mod cli_examples;
mod cli_foe;
mod cli_pcap;
mod cli_run;
mod cli_tools;
mod config_fuzz;
mod demo;
mod docs_book;
mod eds_drives;
mod esi_corpus;
mod esi_profiles;
mod first_user;
mod foreign_devices;
mod fuzz_corpus;
mod generative;
mod homing_runs;
mod jitter_cli;
mod jitter_inprocess;
mod jitter_veth;
mod layering;
mod manual_facts;
mod master_startup;
mod mode_switch_safety;
mod operator_runs;
mod plot;
mod profile_runs;
mod record;
mod recovery_operator;
mod repository;
mod sim_cli;
mod sim_faults_cli;
mod soak_short;
mod untimed;
