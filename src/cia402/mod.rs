//! The pure CiA 402 layer: no I/O, no clocks.
