//! Typed views over EtherCAT frames and datagrams.
