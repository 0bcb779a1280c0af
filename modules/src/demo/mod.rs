//! Demo modules that exercise the runtime core: a counter and a signal generator (sources), a
//! scale/filter (in → out with parameters), a queue producer and a queue consumer that checks
//! order, a printer, and a chaos monkey that makes modules fail.

mod camera;
mod chaos;
mod consumer;
mod counter;
mod printer;
mod producer;
mod scale;
mod signal;

pub use camera::Camera;
pub use chaos::Chaos;
pub use consumer::Consumer;
pub use counter::Counter;
pub use printer::Printer;
pub use producer::Producer;
pub use scale::Scale;
pub use signal::Signal;

use petrel_actors::ModuleRegistry;

/// Registers every demo module type.
pub fn register(registry: &mut ModuleRegistry) {
    registry
        .register::<Counter>()
        .register::<Signal>()
        .register::<Scale>()
        .register::<Producer>()
        .register::<Consumer>()
        .register::<Printer>()
        .register::<Chaos>()
        .register::<Camera>();
}

fn period(ms: i64) -> std::time::Duration {
    std::time::Duration::from_millis(ms.max(1) as u64)
}
