//! Typed views over mailbox, CoE, SDO, SDO information and emergency messages.
