//! Loading plan files: PNML or text plans, with sub-plans resolved next to
//! the file (`subplan.exec` -> `subplan.pnml` in the same directory).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::error::PlanError;
use crate::model::Plan;
use crate::pnml::{parse_pnml, write_pnml};
use crate::text::compile_text;

/// A plan loaded from a file, sub-plans attached.
#[derive(Debug, Clone)]
pub struct LoadedPlan {
    /// The plan.
    pub plan: Arc<Plan>,
    /// The file it came from.
    pub path: PathBuf,
}

/// Reads a text plan, rules or script file (a regular file within
/// [`petrel_actors::files::limits::PLAN`], byte-order mark dropped); bytes that are not
/// UTF-8 are an error at their line and column, as in configs and rules.
pub(crate) fn read_text(path: &Path) -> Result<String, PlanError> {
    read_text_of(path, "plan file")
}

/// [`read_text`] of a file said to be `what` in errors (`rules file`).
fn read_text_of(path: &Path, what: &str) -> Result<String, PlanError> {
    let bytes = read_bytes(path, what)?;
    match String::from_utf8(bytes) {
        Ok(s) => Ok(petrel_actors::files::strip_bom(&s).to_string()),
        Err(e) => {
            let valid = e.utf8_error().valid_up_to();
            let before = String::from_utf8_lossy(&e.as_bytes()[..valid]);
            let count = |n: usize| u32::try_from(n + 1).unwrap_or(u32::MAX);
            let line = count(before.matches('\n').count());
            let column = count(before.rsplit('\n').next().map_or(0, |l| l.chars().count()));
            Err(PlanError::Syntax {
                file: path.display().to_string(),
                line,
                column,
                message: format!(
                    "expected UTF-8 text, found the byte 0x{:02X} (save the file as UTF-8)",
                    e.as_bytes()[valid]
                ),
            })
        }
    }
}

/// Reads a PNML file as text: PNML editors often write ISO-8859-1, so bytes that are not
/// UTF-8 are read as Latin-1.
fn read_pnml_text(path: &Path) -> Result<String, PlanError> {
    Ok(match String::from_utf8(read_bytes(path, "plan file")?) {
        Ok(s) => petrel_actors::files::strip_bom(&s).to_string(),
        Err(e) => e.into_bytes().iter().map(|&b| b as char).collect(),
    })
}

fn read_bytes(path: &Path, what: &str) -> Result<Vec<u8>, PlanError> {
    use petrel_actors::files;
    files::read_bytes(path, what, files::limits::PLAN).map_err(|message| PlanError::Io {
        path: path.to_path_buf(),
        message,
    })
}

/// The file name up to its first dot.
fn stem(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    name.split('.').next().unwrap_or_default().to_string()
}

fn is_pnml(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pnml"))
}

/// Loads a plan: a `.pnml` file, or a text plan (any other extension) with
/// an optional execution-rules file. Executables whose name matches a
/// `NAME.pnml` next to the file become sub-plans (recursively).
pub fn load_plan(path: &Path, rules: Option<&Path>) -> Result<LoadedPlan, PlanError> {
    let plan = if is_pnml(path) {
        if let Some(r) = rules {
            return Err(PlanError::Syntax {
                file: r.display().to_string(),
                line: 1,
                column: 1,
                message: format!(
                    "execution rules apply to text plans only, not to {}",
                    path.display()
                ),
            });
        }
        parse_pnml(
            &read_pnml_text(path)?,
            &path.display().to_string(),
            &stem(path),
        )?
    } else {
        compile_file(path, rules)?
    };
    let mut chain = vec![stem(path)];
    let plan = attach_subplans(plan, path, &mut chain, &mut HashMap::new())?;
    Ok(LoadedPlan {
        plan: Arc::new(plan),
        path: path.to_path_buf(),
    })
}

fn compile_file(path: &Path, rules: Option<&Path>) -> Result<Plan, PlanError> {
    let text = read_text(path)?;
    let rules_text = rules
        .map(|r| read_text_of(r, "rules file").map(|t| (t, r.display().to_string())))
        .transpose()?;
    compile_text(
        &text,
        &path.display().to_string(),
        &stem(path),
        rules_text.as_ref().map(|(t, f)| (t.as_str(), f.as_str())),
    )
}

/// Loads the sub-plans of `plan` (a `name.pnml` beside `path` for each action `name`), and
/// theirs. Each file is read once per load (`loaded`): a sub-plan shared by many plans of a
/// deep hierarchy is parsed once, not once per path to it.
fn attach_subplans(
    mut plan: Plan,
    path: &Path,
    chain: &mut Vec<String>,
    loaded: &mut HashMap<PathBuf, Arc<Plan>>,
) -> Result<Plan, PlanError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    for e in 0..plan.executables().len() {
        let name = plan.executables()[e].name.clone();
        let file = dir.join(format!("{name}.pnml"));
        if name.contains(['/', '\\']) || !file.is_file() {
            continue;
        }
        if chain.contains(&name) {
            chain.push(name.clone());
            return Err(PlanError::SubPlanCycle {
                file: path.display().to_string(),
                name,
                chain: chain.join(" -> "),
            });
        }
        // Stepping, checking and loading recurse once per level: a chain of thousands of
        // files overflowed the stack.
        if chain.len() >= crate::error::MAX_DEPTH {
            let (head, tail) = (&chain[..3], &chain[chain.len() - 2..]);
            return Err(PlanError::SubPlansTooDeep {
                file: path.display().to_string(),
                limit: crate::error::MAX_DEPTH,
                chain: format!(
                    "{} -> ... -> {} -> {name}",
                    head.join(" -> "),
                    tail.join(" -> ")
                ),
            });
        }
        let sub = match loaded.get(&file) {
            Some(sub) => sub.clone(),
            None => {
                chain.push(name.clone());
                let sub = parse_pnml(&read_pnml_text(&file)?, &file.display().to_string(), &name)?;
                let sub = Arc::new(attach_subplans(sub, &file, chain, loaded)?);
                chain.pop();
                loaded.insert(file, sub.clone());
                sub
            }
        };
        plan.set_subplan(e, sub);
    }
    Ok(plan)
}

/// Compiles a text plan (plus optional rules file) to JARP-openable PNML.
pub fn compile_to_pnml(path: &Path, rules: Option<&Path>) -> Result<String, PlanError> {
    if is_pnml(path) {
        return Err(PlanError::Io {
            path: path.to_path_buf(),
            message: "is a PNML plan already; `plan compile` turns a text plan into PNML".into(),
        });
    }
    Ok(write_pnml(&compile_file(path, rules)?))
}
