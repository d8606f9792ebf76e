//! The software EtherCAT slave: emulated slave controllers (ESC) with SII, SyncManagers, FMMUs,
//! mailbox CoE and distributed clocks, and emulated CiA 402 drives behind them.

pub mod coe;
