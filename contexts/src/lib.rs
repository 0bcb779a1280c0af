//! Context subsystem (issue 5): not implemented yet.
