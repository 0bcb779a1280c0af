//! Actions every mission has without a binding (a binding of the same name wins):
//!
//! * `wait_N`: finishes N seconds (on the mission clock) after it starts; `wait_0.5` works.
//!   Timed actions `A|N` use it for their timer.
//! * `log_some_words` / `say_some_words`: logs "some words" when it starts, and finishes.

/// A built-in action.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Builtin {
    /// `wait_N`: seconds.
    Wait(f64),
    /// `log_...` / `say_...`: the text.
    Log(String),
}

/// The built-in action `local` (an action name without its robot prefix) stands for, if any.
pub(crate) fn builtin(local: &str) -> Option<Builtin> {
    if let Some(n) = local.strip_prefix("wait_") {
        return n
            .parse::<f64>()
            .ok()
            .filter(|s| s.is_finite() && *s >= 0.0)
            .map(Builtin::Wait);
    }
    let text = local
        .strip_prefix("log_")
        .or_else(|| local.strip_prefix("say_"))?;
    Some(Builtin::Log(text.replace('_', " ")))
}

/// Why `local` looks like the built-in `wait_N` but is not one (`wait_abc`, `wait_-1`,
/// `wait_1e999`): such an action is an ordinary one that needs a binding, which is seldom
/// what its author meant.
pub(crate) fn not_a_wait(local: &str) -> Option<String> {
    let n = local.strip_prefix("wait_")?;
    if builtin(local).is_some() {
        return None;
    }
    Some(format!(
        "`{local}` is not the built-in wait: `wait_N` takes a number of seconds, finite and at least 0 (`wait_2`, `wait_0.5`), and `{n}` is not one"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn built_in_names() {
        assert_eq!(builtin("wait_20"), Some(Builtin::Wait(20.0)));
        assert_eq!(builtin("wait_0.5"), Some(Builtin::Wait(0.5)));
        assert_eq!(builtin("wait_free"), None);
        assert_eq!(
            builtin("say_hello_world"),
            Some(Builtin::Log("hello world".into()))
        );
        assert_eq!(builtin("log_at_A"), Some(Builtin::Log("at A".into())));
        assert_eq!(builtin("goto_A"), None);
    }

    #[test]
    fn almost_waits_are_named() {
        for almost in ["wait_abc", "wait_-1", "wait_1e999", "wait_NaN", "wait_"] {
            assert!(not_a_wait(almost).is_some(), "{almost}");
        }
        for fine in ["wait_2", "wait_0.5", "goto_A", "waiting"] {
            assert_eq!(not_a_wait(fine), None, "{fine}");
        }
    }
}
