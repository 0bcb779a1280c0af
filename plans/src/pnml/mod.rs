//! PNML as PNP's editor (JARP) and generator write it.

mod depth;
mod read;
mod write;

pub use read::parse_pnml;
pub use write::write_pnml;
