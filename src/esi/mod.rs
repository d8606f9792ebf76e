//! ESI (EtherCAT Slave Information, ETG.2000) XML parsing.
