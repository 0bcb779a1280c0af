//! petrel: an async, actor-based, context-aware mission runtime for robots.
//!
//! This crate is the facade: it re-exports the runtime core ([`actors`]), the built-in
//! modules ([`modules`]), the plans library and its `mission.pnp` module ([`plans`]), and holds the `petrel` command line. To add your own module types,
//! build your own binary with [`Petrel`]:
//!
//! ```no_run
//! use petrel::actors::{Context, Input, Module, Output, Ports, Schedule};
//!
//! struct Double { input: Input<f64>, out: Output<f64> }
//!
//! impl Module for Double {
//!     const TYPE: &'static str = "my.double";
//!     const DESCRIPTION: &'static str = "Writes twice its input.";
//!     fn declare(ports: &mut Ports) -> Self {
//!         Double { input: ports.input("in/value", 0.0, "value"), out: ports.output("out/value", 0.0, "2 * value") }
//!     }
//!     fn schedule(&self) -> Schedule { Schedule::new().on_change(&self.input) }
//!     async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
//!         self.out.set(2.0 * self.input.value());
//!         Ok(())
//!     }
//! }
//!
//! fn main() -> std::process::ExitCode {
//!     petrel::Petrel::new().module::<Double>().main()
//! }
//! ```

pub mod cli;

pub use petrel_actors as actors;
pub use petrel_console as console;
pub use petrel_contexts as contexts;
pub use petrel_modules as modules;
pub use petrel_plans as plans;
pub use petrel_record as record;
pub use petrel_team as team;

use petrel_actors::{Module, ModuleRegistry};

/// Loads an agent config as `petrel run` and `petrel check` do: its `contexts:` field adds the
/// `contexts` module, and missions run on the agent's simulator clock when it has one.
pub fn load(
    config: impl AsRef<std::path::Path>,
) -> Result<petrel_actors::ConfigFile, petrel_actors::ConfigErrors> {
    cli::load(&config.as_ref().to_path_buf(), &[])
}

/// What `petrel check` runs on one agent's config: builds its registry and asks every module
/// type, context manager and mission what it would refuse at init. A config that passes starts.
pub fn check(
    file: &petrel_actors::ConfigFile,
    registry: &petrel_actors::ModuleRegistry,
) -> Result<(), petrel_actors::ConfigErrors> {
    cli::check_all(file, registry).map(|_| ())
}

/// Builds a `petrel` command line with the built-in module types plus your own.
#[derive(Clone)]
pub struct Petrel {
    registry: ModuleRegistry,
}

impl Default for Petrel {
    fn default() -> Self {
        Self::new()
    }
}

impl Petrel {
    /// The built-in module types.
    pub fn new() -> Self {
        let mut registry = petrel_modules::builtin();
        petrel_contexts::register(&mut registry);
        petrel_plans::register(&mut registry);
        petrel_record::register(&mut registry);
        Petrel { registry }
    }

    /// Adds module type `M`.
    pub fn module<M: Module>(mut self) -> Self {
        self.registry.register::<M>();
        self
    }

    /// The module types known so far.
    pub fn registry(&self) -> &ModuleRegistry {
        &self.registry
    }

    /// Parses the process arguments and runs the `petrel` command line.
    pub fn main(self) -> std::process::ExitCode {
        cli::main(self.registry, std::env::args_os())
    }

    /// Runs the `petrel` command line with `args` (the first names the program), e.g. from a
    /// test of your own module types.
    pub fn main_with<I, T>(self, args: I) -> std::process::ExitCode
    where
        I: IntoIterator<Item = T>,
        T: Into<std::ffi::OsString>,
    {
        cli::main(self.registry, args.into_iter().map(Into::into))
    }
}
