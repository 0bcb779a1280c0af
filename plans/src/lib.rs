//! Petri Net Plans for petrel.
