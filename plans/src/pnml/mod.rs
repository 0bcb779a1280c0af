//! PNML as PNP's editor (JARP) and generator write it.

mod read;
mod write;

pub use read::parse_pnml;
pub use write::write_pnml;
