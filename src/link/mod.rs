//! Ethernet frame I/O shared by the master and the software slave.
