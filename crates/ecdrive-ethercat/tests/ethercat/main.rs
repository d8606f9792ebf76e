//! The EtherCAT master's tests, against the software slave: start-up, CoE, the cycle (its allocation and system-call audit), faults, scale.
//!
//! One test binary for the crate `ecdrive-ethercat`: each module was a test file of its own.

// The allocation audits count the allocations a thread makes inside its window.
#[global_allocator]
static ALLOC: ecdrive_core::rt::audit::CountingAlloc = ecdrive_core::rt::audit::CountingAlloc;

mod support;

mod answers;
mod app_cycle;
mod cycle_audit;
mod esi_errors;
mod faults_master;
mod master_coe;
mod master_cycle_generic;
mod master_drives;
mod master_segment_lost;
mod master_veth;
mod own_frames;
mod scale;
