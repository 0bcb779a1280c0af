//! Panics of modules go through tracing, not around it.
//!
//! Rust's default panic hook prints the message (and with `RUST_BACKTRACE` a backtrace)
//! straight to standard error, between log lines and outside the module's span, so JSON log
//! consumers never see it. Module code runs inside [`catching`]: a panic there is reported once,
//! as an ERROR event in the span being polled (the module's), with its message and location
//! and, when `RUST_BACKTRACE` asks for one, the backtrace as a field; the module then fails
//! with a reason that names the same location, which the supervisor's failure event carries.
//! Panics anywhere else keep the hook that was installed before.
//!
//! A backtrace is captured in the hook but written from a thread of its own (in the module's
//! span, entered there): resolving its symbols reads the binary's debug info, hundreds of ms
//! the first time, which held the agent's thread (every other module of the agent waited, and
//! the held watcher reported the panicking module as a step that does not return). An agent's
//! stop waits for those threads ([`flush`]), so a run ending after a panic keeps its report.

use std::cell::{Cell, RefCell};
use std::future::Future;
use std::panic::{AssertUnwindSafe, PanicHookInfo};
use std::pin::Pin;
use std::sync::Once;
use std::task::{Context, Poll};

thread_local! {
    /// While this thread polls module code, the span of that module (a pointer into the
    /// [`Catching`] being polled, valid for that poll); null otherwise.
    static IN_MODULE: Cell<*const tracing::Span> = const { Cell::new(std::ptr::null()) };
    /// What the hook saw of the last module panic on this thread: `panicked at LOC: MSG`.
    static LAST: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Installs the hook (once per process; later calls do nothing).
pub fn install() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let module = IN_MODULE.with(Cell::get);
            if !module.is_null() {
                // SAFETY: set by `Catching::poll` to its own span for the length of the poll,
                // and this hook runs inside that poll (before unwinding leaves it).
                report(info, unsafe { &*module });
            } else {
                previous(info);
            }
        }));
    });
}

fn report(info: &PanicHookInfo<'_>, module: &tracing::Span) {
    let message = message_of(info.payload());
    let location = info
        .location()
        .map(|l| format!("{}:{}:{}", l.file(), l.line(), l.column()))
        .unwrap_or_else(|| "an unknown place".into());
    LAST.with(|last| *last.borrow_mut() = Some(format!("panicked at {location}: {message}")));
    let backtrace = std::backtrace::Backtrace::capture();
    if backtrace.status() != std::backtrace::BacktraceStatus::Captured {
        tracing::error!(panic.location = %location, "panicked: {message}");
        return;
    }
    // The spans entered on this thread, outermost first, entered again on the writer's thread
    // (which starts with none): the module's, then the one being polled (a step's).
    let spans = [module.clone(), tracing::Span::current()];
    let (at, what) = (location.clone(), message.clone());
    let spawned = std::thread::Builder::new()
        .name("petrel-backtrace".into())
        .spawn(move || {
            let _module = spans[0].enter();
            let _inner = spans[1].enter();
            tracing::error!(panic.location = %at, backtrace = %backtrace, "panicked: {what}");
        });
    match spawned {
        Ok(handle) => {
            // Reports already written are joined here, so that a module panicking all day
            // leaves no finished threads waiting to be joined.
            let done: Vec<_> = {
                let mut pending = PENDING.lock();
                let (done, running) = pending.drain(..).partition(|h| h.is_finished());
                *pending = running;
                pending.push(handle);
                done
            };
            for finished in done {
                let _ = finished.join();
            }
        }
        // No thread to spare: the report without its backtrace rather than none.
        Err(e) => tracing::error!(
            panic.location = %location,
            "panicked: {message} (no backtrace: no thread to write it: {e})"
        ),
    }
}

/// Backtrace reports still being written (see [`report`]).
static PENDING: parking_lot::Mutex<Vec<std::thread::JoinHandle<()>>> =
    parking_lot::Mutex::new(Vec::new());

/// Whether backtraces of module panics are still being written (see [`flush`]).
pub(crate) fn pending() -> bool {
    !PENDING.lock().is_empty()
}

/// Waits until the backtraces of module panics so far are written, so that a process ending
/// right after a panic does not lose its report.
pub(crate) fn flush() {
    let pending = std::mem::take(&mut *PENDING.lock());
    for handle in pending {
        let _ = handle.join();
    }
}

pub(crate) fn message_of(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".into()
    }
}

/// Runs `future` as the code of the module whose span is `module`: a panic inside it becomes
/// `Err` with the reason the hook recorded (or the panic's message, when the hook is not
/// installed), and is reported in that span.
pub(crate) fn catching<F: Future>(module: &tracing::Span, future: F) -> Catching<F> {
    Catching {
        inner: Box::pin(future),
        module: module.clone(),
    }
}

/// The future of [`catching`].
pub(crate) struct Catching<F> {
    inner: Pin<Box<F>>,
    module: tracing::Span,
}

impl<F: Future> Future for Catching<F> {
    type Output = Result<F::Output, String>;

    fn poll(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Self::Output> {
        // Reset even when unwinding, so code polled later on this thread is not mistaken for
        // module code.
        struct Leave(*const tracing::Span);
        impl Drop for Leave {
            fn drop(&mut self) {
                IN_MODULE.with(|m| m.set(self.0));
            }
        }
        let this = &mut *self;
        let _leave = Leave(IN_MODULE.with(|m| m.replace(&this.module)));
        let inner = &mut this.inner;
        match std::panic::catch_unwind(AssertUnwindSafe(|| inner.as_mut().poll(cx))) {
            Ok(Poll::Ready(out)) => Poll::Ready(Ok(out)),
            Ok(Poll::Pending) => Poll::Pending,
            Err(payload) => {
                let recorded = LAST.with(|last| last.borrow_mut().take());
                Poll::Ready(Err(recorded.unwrap_or_else(|| message_of(&*payload))))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn a_panic_in_module_code_becomes_an_error_naming_where() {
        install();
        let line = line!() + 2;
        let result = catching(&tracing::Span::none(), async {
            panic!("wheel encoder exploded");
        })
        .await;
        let reason = result.unwrap_err();
        assert!(
            reason.starts_with(&format!("panicked at {}:{line}:", file!())),
            "{reason}"
        );
        assert!(reason.ends_with(": wheel encoder exploded"), "{reason}");
        assert!(IN_MODULE.with(Cell::get).is_null(), "left module code");
        assert_eq!(catching(&tracing::Span::none(), async { 7 }).await, Ok(7));
    }
}
