//! Property declarations: what a module says it reads, writes and exposes.
//!
//! A module's [`Module::declare`](crate::Module::declare) receives [`Ports`] and builds itself
//! from the handles Ports returns. The same declaration runs in two modes: *fresh* (creating
//! new cells, used to describe a module type, to check configs, and on first start) and
//! *bound* (handing out the cells the blackboard already holds, so that a restarted module
//! finds its parameters, state and queue positions as its previous instance left them).

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use crate::cell::Endpoint;
use crate::handle::{Input, Output, QueueReader, QueueWriter};
use crate::queue::{QueueCore, ReaderEndpoint, DEFAULT_CAPACITY};
use crate::step_clock::StepClock;
use crate::types::PropertyType;
use crate::value::{AnyValue, TypeInfo};

pub use crate::property_kind::PropertyKind;

/// One declared property, as `petrel modules describe` shows it.
#[derive(Clone)]
pub struct PropertyDecl {
    /// Path inside the module, e.g. `params/factor`.
    pub path: String,
    /// Its role.
    pub kind: PropertyKind,
    /// Its value type (the item type for queues).
    pub type_info: TypeInfo,
    /// The default value (none for queues).
    pub default: Option<AnyValue>,
    /// One line saying what it is.
    pub doc: String,
    /// Default capacity, for queue outputs.
    pub capacity: Option<usize>,
    /// The values a numeric parameter accepts (every `f64` parameter: finite ones at least).
    pub(crate) range: Option<crate::range::RangeCheck>,
    /// A parameter its module reads only when it starts (see [`Ports::read_at_start`]).
    pub(crate) read_at_start: bool,
    /// What a value must look like beyond its numbers' range (see [`Ports::accept_last`]).
    pub(crate) shape: Option<Shape>,
}

/// Says, of a value, how people read it if it is refused.
type ShapeRule = dyn Fn(&AnyValue) -> Option<String> + Send + Sync;

/// A parameter's rule on a whole value (a list's length, its bounds' order), with what it
/// takes in words: checked wherever a range is (configs, `petrel check`, tools, rules,
/// bindings).
#[derive(Clone)]
pub(crate) struct Shape {
    /// The value as people read it, if refused.
    pub refuses: Arc<ShapeRule>,
    pub expected: &'static str,
}

impl PropertyDecl {
    /// Whether its module reads it only when it starts, so a running agent refuses to change
    /// it (see [`Ports::read_at_start`]).
    pub fn is_read_at_start(&self) -> bool {
        self.read_at_start
    }

    /// What it accepts, for a listing: a numeric parameter's range (`0..=1`) or the words a
    /// text property takes (`sine|square`); `None` when it takes any value of its type.
    pub fn accepts(&self) -> Option<String> {
        if let Some(shape) = &self.shape {
            return Some(shape.expected.to_string());
        }
        let check = self.range?;
        match check.choices() {
            [] => Some(check.range.to_string()),
            words => {
                let shown: Vec<&str> = words
                    .iter()
                    .map(|w| if w.is_empty() { "\"\"" } else { w })
                    .collect();
                Some(shown.join("|"))
            }
        }
    }

    /// The default value as RON text, or `-` for queues.
    pub fn default_text(&self) -> String {
        match &self.default {
            Some(v) => self
                .type_info
                .to_ron(v)
                .unwrap_or_else(|e| format!("<{e}>")),
            None => match self.capacity {
                Some(c) => format!("queue, capacity {c}"),
                None => "queue".to_string(),
            },
        }
    }
}

/// A cell, queue or reader a declaration produced or was bound to.
#[derive(Clone)]
pub(crate) enum Handle {
    Value(Arc<Endpoint>),
    QueueOut(Arc<QueueCore>),
    QueueIn(Arc<ReaderEndpoint>),
}

static NEXT_READER: AtomicU64 = AtomicU64::new(1);

/// The declaration context handed to [`Module::declare`](crate::Module::declare).
pub struct Ports {
    module: String,
    /// The module's step time, shared by the handles that write.
    pub(crate) clock: Arc<StepClock>,
    bound: Option<HashMap<String, Handle>>,
    pub(crate) decls: Vec<PropertyDecl>,
    pub(crate) handles: Vec<Handle>,
    pub(crate) errors: Vec<String>,
}

impl Ports {
    /// Declarations that create fresh cells, for a module named `module`.
    pub(crate) fn fresh(module: &str) -> Self {
        Ports {
            module: module.to_string(),
            clock: Arc::default(),
            bound: None,
            decls: Vec::new(),
            handles: Vec::new(),
            errors: Vec::new(),
        }
    }

    /// Declarations that hand out the blackboard's existing cells.
    pub(crate) fn bound(module: &str, handles: HashMap<String, Handle>) -> Self {
        Ports {
            bound: Some(handles),
            ..Ports::fresh(module)
        }
    }

    /// The name of the module instance being declared.
    pub fn module_name(&self) -> &str {
        &self.module
    }

    /// Declares an input `in/...` with its default value.
    pub fn input<T: PropertyType>(&mut self, path: &str, default: T, doc: &str) -> Input<T> {
        Input::new(self.value(PropertyKind::Input, path, default, doc))
    }

    /// Declares a parameter `params/...` with its default value. An `f64` parameter accepts
    /// finite values (use [`param_in`](Ports::param_in) to say which); a structured one (a
    /// pose, a point, a list) only finite numbers in every field.
    pub fn param<T: PropertyType>(&mut self, path: &str, default: T, doc: &str) -> Input<T> {
        let input = Input::new(self.value(PropertyKind::Param, path, default, doc));
        let ti = TypeInfo::of::<T>();
        if ti == TypeInfo::of::<f64>() {
            self.limit_last(crate::Range::FINITE);
        } else if ![
            TypeInfo::of::<i64>(),
            TypeInfo::of::<bool>(),
            TypeInfo::of::<String>(),
        ]
        .contains(&ti)
        {
            // Structured values (poses, points, lists): every number in them finite.
            let decl = self.decls.last_mut().expect("just declared");
            decl.range = Some(crate::range::RangeCheck::finite_fields::<T>());
        }
        input
    }

    /// Declares a numeric parameter that accepts only values within `range`: a config, an
    /// overlay, a tool or a context rule setting another value is refused, naming the range.
    pub fn param_in<T: crate::Numeric>(
        &mut self,
        path: &str,
        default: T,
        range: crate::Range,
        doc: &str,
    ) -> Input<T> {
        let input = Input::new(self.value(PropertyKind::Param, path, default, doc));
        self.limit_last(range);
        input
    }

    /// Declares a word parameter that takes only one of `choices` (a waveform, a drive, a
    /// mode): a config, an overlay, a tool or a context rule writing another word is refused,
    /// naming the choices, at load, at `petrel check` and at run time alike.
    pub fn param_one_of(
        &mut self,
        path: &str,
        default: &'static str,
        choices: &'static [&'static str],
        doc: &str,
    ) -> Input<String> {
        let input = Input::new(self.value(PropertyKind::Param, path, default.to_string(), doc));
        if !choices.contains(&default) {
            self.errors.push(format!(
                "parameter `{path}` of module `{}`: its default {default:?} is not one of its choices",
                self.module
            ));
        }
        self.check_last(crate::range::RangeCheck::one_of(choices));
        input
    }

    /// Checks the values of the property declared last with `check` (see [`RangeCheck`]).
    ///
    /// [`RangeCheck`]: crate::range::RangeCheck
    pub(crate) fn check_last(&mut self, check: crate::range::RangeCheck) {
        let decl = self.decls.last_mut().expect("just declared");
        decl.range = Some(check);
    }

    fn limit_last(&mut self, range: crate::Range) {
        let check = crate::range::RangeCheck::new(range);
        let decl = self.decls.last_mut().expect("just declared");
        if let Some(default) = &decl.default {
            if check.refuses(default).is_some() {
                self.errors.push(format!(
                    "parameter `{}` of module `{}`: its default is outside its range {range}",
                    decl.path, self.module
                ));
            }
        }
        decl.range = Some(check);
    }

    /// Marks parameters (declared already) that the module reads only when it starts (in
    /// `init`, or into a core built there): a running agent refuses to change them, from a
    /// tool, a context rule or a plan binding, and `petrel check` refuses rules and bindings
    /// that would. Without it such a write was taken and did nothing, or, when the value was
    /// one `init` refuses, made the module's next restart fail. Configs, overlays and
    /// snapshots set them as before, ahead of the start. Like ROS 2's read-only parameters.
    pub fn read_at_start(&mut self, paths: &[&str]) {
        for path in paths {
            match self.decls.iter_mut().find(|d| d.path == *path) {
                Some(d) if d.kind == PropertyKind::Param => d.read_at_start = true,
                _ => self.errors.push(format!(
                    "`{path}` of module `{}` is marked read at start but is no parameter it declared",
                    self.module
                )),
            }
        }
    }

    /// Adds a rule on the whole value of the parameter declared last (of type `T`): `accepts`
    /// says whether a value is one it takes, `expected` says in words what it takes (for the
    /// message and `petrel modules describe`). For values whose numbers are each in range but
    /// that do not fit together (`[x0, y0, x1, y1]` with x0 > x1, a list of the wrong length):
    /// refused at load, by `petrel check`, and from tools, rules and bindings while running,
    /// rather than failing the module's step or its next start.
    pub fn accept_last<T: PropertyType>(
        &mut self,
        accepts: fn(&T) -> bool,
        expected: &'static str,
    ) {
        let Some(decl) = self
            .decls
            .last_mut()
            .filter(|d| d.kind == PropertyKind::Param)
        else {
            self.errors.push(format!(
                "module `{}`: a value rule ({expected}) that follows no parameter",
                self.module
            ));
            return;
        };
        if decl.type_info != TypeInfo::of::<T>() {
            self.errors.push(format!(
                "`{}` of module `{}`: a value rule for another type than its own",
                decl.path, self.module
            ));
            return;
        }
        // Shown short: numbers as people read them (1e308, not 309 digits), long lists cut.
        let refuses = move |value: &AnyValue| {
            let typed = value.downcast_ref::<T>()?;
            (!accepts(typed)).then(|| TypeInfo::of::<T>().short(value))
        };
        if let Some(default) = &decl.default {
            if refuses(default).is_some() {
                self.errors.push(format!(
                    "parameter `{}` of module `{}`: its default is not {expected}",
                    decl.path, self.module
                ));
            }
        }
        decl.shape = Some(Shape {
            refuses: Arc::new(refuses),
            expected,
        });
    }

    /// Declares an output `out/...` with its initial value.
    pub fn output<T: PropertyType>(&mut self, path: &str, initial: T, doc: &str) -> Output<T> {
        Output::new(
            self.value(PropertyKind::Output, path, initial, doc),
            self.clock.clone(),
        )
    }

    /// Declares a state property `state/...` with its initial value.
    pub fn state<T: PropertyType>(&mut self, path: &str, initial: T, doc: &str) -> Output<T> {
        Output::new(
            self.value(PropertyKind::State, path, initial, doc),
            self.clock.clone(),
        )
    }

    /// Declares an output queue `out/...` holding at most `capacity` unread items
    /// (configs may change the capacity).
    pub fn queue_out<T: PropertyType>(
        &mut self,
        path: &str,
        capacity: usize,
        doc: &str,
    ) -> QueueWriter<T> {
        let ti = TypeInfo::of::<T>();
        self.declare(PropertyKind::QueueOut, path, ti, None, doc, Some(capacity));
        let core = match self.take_bound(path, ti) {
            Some(Handle::QueueOut(core)) => core,
            _ => QueueCore::new(&self.key(path), ti, capacity),
        };
        self.handles.push(Handle::QueueOut(core.clone()));
        QueueWriter::new(core, self.clock.clone())
    }

    /// Declares an input queue `in/...`: link it to an output queue to receive its items.
    pub fn queue_in<T: PropertyType>(&mut self, path: &str, doc: &str) -> QueueReader<T> {
        let ti = TypeInfo::of::<T>();
        self.declare(PropertyKind::QueueIn, path, ti, None, doc, None);
        let reader = match self.take_bound(path, ti) {
            Some(Handle::QueueIn(reader)) => reader,
            _ => {
                // An unlinked queue input reads a private queue nobody pushes to.
                let key = self.key(path);
                let private = QueueCore::new(&key, ti, DEFAULT_CAPACITY);
                ReaderEndpoint::new(
                    NEXT_READER.fetch_add(1, Ordering::Relaxed),
                    &key,
                    ti,
                    private,
                )
            }
        };
        self.handles.push(Handle::QueueIn(reader.clone()));
        QueueReader::new(reader)
    }

    /// Declares a runtime-owned property (`enabled`, `stats/...`).
    pub(crate) fn builtin<T: PropertyType>(
        &mut self,
        kind: PropertyKind,
        path: &str,
        default: T,
        doc: &str,
    ) -> Output<T> {
        Output::new(self.value(kind, path, default, doc), self.clock.clone())
    }

    fn value<T: PropertyType>(
        &mut self,
        kind: PropertyKind,
        path: &str,
        default: T,
        doc: &str,
    ) -> Arc<Endpoint> {
        let ti = TypeInfo::of::<T>();
        let default: AnyValue = Arc::new(default);
        self.declare(kind, path, ti, Some(default.clone()), doc, None);
        let ep = match self.take_bound(path, ti) {
            Some(Handle::Value(ep)) => ep,
            _ => Endpoint::new(&self.key(path), ti, default),
        };
        self.handles.push(Handle::Value(ep.clone()));
        ep
    }

    fn key(&self, path: &str) -> String {
        format!("{}/{}", self.module, path)
    }

    fn declare(
        &mut self,
        kind: PropertyKind,
        path: &str,
        type_info: TypeInfo,
        default: Option<AnyValue>,
        doc: &str,
        capacity: Option<usize>,
    ) {
        let well_formed = path.split('/').all(crate::url::valid_segment);
        let prefixed = match kind {
            PropertyKind::Enabled => path == "enabled",
            _ => path.starts_with(kind.prefix()) && path.len() > kind.prefix().len(),
        };
        if !well_formed || !prefixed {
            self.errors.push(format!(
                "property `{path}` of module `{}`: a {kind} path must look like `{}name` (letters, digits, `_`, `-`, `.`)",
                self.module,
                kind.prefix()
            ));
        } else if self.decls.iter().any(|d| d.path == path) {
            self.errors.push(format!(
                "property `{path}` of module `{}` is declared twice",
                self.module
            ));
        }
        self.decls.push(PropertyDecl {
            path: path.to_string(),
            kind,
            type_info,
            default,
            doc: doc.to_string(),
            capacity,
            range: None,
            read_at_start: false,
            shape: None,
        });
    }

    fn take_bound(&mut self, path: &str, type_info: TypeInfo) -> Option<Handle> {
        let handle = self.bound.as_mut()?.remove(path);
        let found = match &handle {
            Some(Handle::Value(e)) => Some(e.type_info()),
            Some(Handle::QueueOut(q)) => Some(q.type_info),
            Some(Handle::QueueIn(r)) => Some(r.type_info),
            None => None,
        };
        match found {
            Some(t) if t == type_info => handle,
            Some(t) => {
                self.errors.push(format!(
                    "property `{path}` of module `{}` is a {} in the blackboard but is declared as {}",
                    self.module,
                    t.name(),
                    type_info.name()
                ));
                None
            }
            None => {
                self.errors.push(format!(
                    "property `{path}` of module `{}` is not in the blackboard",
                    self.module
                ));
                None
            }
        }
    }
}
