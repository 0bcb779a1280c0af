//! Panics of modules go through tracing, not around it.
//!
//! Rust's default panic hook prints the message (and with `RUST_BACKTRACE` a backtrace)
//! straight to standard error, between log lines and outside the module's span, so JSON log
//! consumers never see it. Module code runs inside [`catching`]: a panic there is reported once,
//! as an ERROR event in the span being polled (the module's), with its message and location
//! and, when `RUST_BACKTRACE` asks for one, the backtrace as a field; the module then fails
//! with a reason that names the same location, which the supervisor's failure event carries.
//! Panics anywhere else keep the hook that was installed before.

use std::cell::{Cell, RefCell};
use std::future::Future;
use std::panic::{AssertUnwindSafe, PanicHookInfo};
use std::pin::Pin;
use std::sync::Once;
use std::task::{Context, Poll};

thread_local! {
    /// Set while this thread polls module code.
    static IN_MODULE: Cell<bool> = const { Cell::new(false) };
    /// What the hook saw of the last module panic on this thread: `panicked at LOC: MSG`.
    static LAST: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Installs the hook (once per process; later calls do nothing).
pub fn install() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if IN_MODULE.with(Cell::get) {
                report(info);
            } else {
                previous(info);
            }
        }));
    });
}

fn report(info: &PanicHookInfo<'_>) {
    let message = message_of(info.payload());
    let location = info
        .location()
        .map(|l| format!("{}:{}:{}", l.file(), l.line(), l.column()))
        .unwrap_or_else(|| "an unknown place".into());
    let backtrace = std::backtrace::Backtrace::capture();
    if backtrace.status() == std::backtrace::BacktraceStatus::Captured {
        tracing::error!(panic.location = %location, backtrace = %backtrace, "panicked: {message}");
    } else {
        tracing::error!(panic.location = %location, "panicked: {message}");
    }
    LAST.with(|last| *last.borrow_mut() = Some(format!("panicked at {location}: {message}")));
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

/// Runs `future` as module code: a panic inside it becomes `Err` with the reason the hook
/// recorded (or the panic's message, when the hook is not installed).
pub(crate) fn catching<F: Future>(future: F) -> Catching<F> {
    Catching {
        inner: Box::pin(future),
    }
}

/// The future of [`catching`].
pub(crate) struct Catching<F> {
    inner: Pin<Box<F>>,
}

impl<F: Future> Future for Catching<F> {
    type Output = Result<F::Output, String>;

    fn poll(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Self::Output> {
        // Reset even when unwinding, so code polled later on this thread is not mistaken for
        // module code.
        struct Leave(bool);
        impl Drop for Leave {
            fn drop(&mut self) {
                IN_MODULE.with(|m| m.set(self.0));
            }
        }
        let _leave = Leave(IN_MODULE.with(|m| m.replace(true)));
        let inner = &mut self.inner;
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
        let result = catching(async {
            panic!("wheel encoder exploded");
        })
        .await;
        let reason = result.unwrap_err();
        assert!(
            reason.starts_with(&format!("panicked at {}:{line}:", file!())),
            "{reason}"
        );
        assert!(reason.ends_with(": wheel encoder exploded"), "{reason}");
        assert!(!IN_MODULE.with(Cell::get), "left module code");
        assert_eq!(catching(async { 7 }).await, Ok(7));
    }
}
