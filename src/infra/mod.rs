//! Infrastructure every layer may use: the error enum, atomic output files, hashing of run
//! identities, the journal of finished work (resumable runs) and progress observers.

pub mod error;
pub mod identity;
pub mod journal;
pub mod output;
pub mod progress;
