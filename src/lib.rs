//! petrel: facade.
pub use petrel_actors as actors;
