//! The software slave's tests: ESC registers, mailbox, CoE and FoE, faults, the emulated drives against the manuals through the wire, and the independent masters (SOEM, KickCAT, ethercrab) driving it.
//!
//! One test binary for the crate `ecdrive-sim`: each module was a test file of its own.

// The allocation audits count the allocations a thread makes inside its window.
#[global_allocator]
static ALLOC: ecdrive_core::rt::audit::CountingAlloc = ecdrive_core::rt::audit::CountingAlloc;

mod coe_util;
mod support;

mod coe_fuzz;
mod coe_info;
mod coe_mailbox;
mod coe_sdo;
mod coe_store;
mod drives_audit;
mod drives_comm;
mod drives_dictionary;
mod drives_ethercrab;
mod drives_fsa;
mod drives_homing;
mod drives_motion;
mod drives_sii;
mod emulation_independence;
mod foe_fuzz;
mod jitter_sim_stats;
mod sim_cycle_audit;
mod sim_esc;
mod sim_ethercrab;
mod sim_faults;
mod sim_faults_alloc;
mod sim_faults_ethercrab;
mod sim_fuzz;
mod sim_kickcat;
mod sim_mailbox;
mod sim_soem;
