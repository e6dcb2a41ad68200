//! Input/output above the analyses: the exporters that write each command's result (files
//! and the console report) from the plain structs the library returns.

pub mod export;
