//! Drive profiles: one file per drive, identity, defaults, quirks and alarm tables as data.
