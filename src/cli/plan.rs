//! `petrel plan ...`: load, check, draw, compile and simulate Petri Net Plans.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Subcommand;
use petrel_plans::{
    check_with, compile_to_pnml, load_plan, simulate, to_dot, CheckOptions, LoadedPlan, PlanStatus,
    Script, DEFAULT_MAX_STATES, DEFAULT_MAX_STEPS,
};

use super::EXIT_BAD_INPUT;

use super::stdout::{say, sayln};
use super::{EXIT_FAILED as EXIT_PLAN_FAILED, EXIT_STILL_RUNNING};

#[derive(Subcommand)]
pub(crate) enum PlanCommand {
    /// Loads a plan (PNML or text), resolves sub-plans, lists actions and conditions, and
    /// analyses it: unreachable transitions, dead ends, unsafe places, unreachable goal.
    Check {
        /// The plan: `.pnml`, or a text plan (any other extension).
        plan: PathBuf,
        /// Execution rules for a text plan.
        #[arg(long)]
        rules: Option<PathBuf>,
        /// Markings explored at most (1 or more); beyond, the report is marked incomplete.
        #[arg(long, default_value_t = DEFAULT_MAX_STATES as u64, value_parser = clap::value_parser!(u64).range(1..))]
        max_states: u64,
    },
    /// Prints the plan as a Graphviz graph (`petrel plan dot P | dot -Tsvg > p.svg`).
    Dot {
        /// The plan.
        plan: PathBuf,
        /// Execution rules for a text plan.
        #[arg(long)]
        rules: Option<PathBuf>,
    },
    /// Compiles a text plan (and rules) to PNML that the JARP editor opens.
    Compile {
        /// The text plan.
        plan: PathBuf,
        /// Execution rules.
        #[arg(long)]
        rules: Option<PathBuf>,
        /// Where to write the PNML.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Runs the plan against a scripted environment; prints one JSON object per step.
    ///
    /// Exit code: 0 when the plan reaches its goal, 1 when it fails, 4 when --steps runs out
    /// with the plan still running, 2 on bad input.
    Simulate {
        /// The plan.
        plan: PathBuf,
        /// Execution rules for a text plan.
        #[arg(long)]
        rules: Option<PathBuf>,
        /// A script file, or `-` to read it from standard input: lines `finish A N`,
        /// `fail A N`, `cond NAME FROM TO`. Without one every action finishes after 2 steps
        /// and every condition is false.
        #[arg(long, value_name = "FILE|-")]
        script: Option<PathBuf>,
        /// Stop after this many steps if the plan has not ended.
        #[arg(long, default_value_t = DEFAULT_MAX_STEPS)]
        steps: u64,
    },
}

pub(crate) fn run(command: PlanCommand) -> ExitCode {
    match command {
        PlanCommand::Check {
            plan,
            rules,
            max_states,
        } => with_plan(&plan, rules.as_deref(), |loaded| {
            let max_states = usize::try_from(max_states).unwrap_or(usize::MAX);
            let report = check_with(&loaded.plan, &CheckOptions { max_states });
            say!("{report}");
            if report.is_ok() {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(EXIT_PLAN_FAILED)
            }
        }),
        PlanCommand::Dot { plan, rules } => with_plan(&plan, rules.as_deref(), |loaded| {
            say!("{}", to_dot(&loaded.plan));
            ExitCode::SUCCESS
        }),
        PlanCommand::Compile {
            plan,
            rules,
            output,
        } => compile(&plan, rules.as_deref(), &output),
        PlanCommand::Simulate {
            plan,
            rules,
            script,
            steps,
        } => with_plan(&plan, rules.as_deref(), |loaded| {
            let script = match &script {
                None => Script::default(),
                Some(path) => {
                    let read = if path.as_os_str() == "-" {
                        std::io::read_to_string(std::io::stdin())
                    } else {
                        std::fs::read_to_string(path)
                    };
                    let text = match read {
                        Ok(text) => text,
                        Err(e) => {
                            return bad_input(format!(
                                "{}: cannot read script: {e}",
                                path.display()
                            ))
                        }
                    };
                    let file = path.display().to_string();
                    match Script::parse(&text, &file)
                        .and_then(|s| s.check(&loaded.plan, &file).map(|()| s))
                    {
                        Ok(script) => script,
                        Err(e) => return bad_input(e.to_string()),
                    }
                }
            };
            let status = simulate(&loaded.plan, &script, steps, &mut std::io::stdout().lock());
            match status {
                Ok(PlanStatus::Fail) => ExitCode::from(EXIT_PLAN_FAILED),
                Ok(PlanStatus::Running) => ExitCode::from(EXIT_STILL_RUNNING),
                Ok(PlanStatus::Goal) => ExitCode::SUCCESS,
                // Reported by `stdout::finish`, as for every command.
                Err(e) => super::stdout::keep_failure(e),
            }
        }),
    }
}

fn with_plan(
    path: &Path,
    rules: Option<&Path>,
    then: impl FnOnce(LoadedPlan) -> ExitCode,
) -> ExitCode {
    match load_plan(path, rules) {
        Ok(loaded) => then(loaded),
        Err(e) => bad_input(e.to_string()),
    }
}

fn bad_input(message: String) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(EXIT_BAD_INPUT)
}

/// `plan compile`: the PNML written to `output`, which must not be an input of the
/// compilation nor a device, FIFO or folder (it would be replaced by the file written).
fn compile(plan: &Path, rules: Option<&Path>, output: &Path) -> ExitCode {
    let pnml = match compile_to_pnml(plan, rules) {
        Ok(pnml) => pnml,
        Err(e) => return bad_input(e.to_string()),
    };
    if refuses_overwrite(output, plan, rules) {
        return bad_input(format!(
            "{}: -o names an input of the compilation; write the PNML elsewhere",
            output.display()
        ));
    }
    if let Some(problem) = petrel_actors::files::output_problem(output, &[], "out/plan.pnml") {
        return bad_input(format!("-o: {problem}"));
    }
    match petrel_actors::files::write_atomically(output, pnml.as_bytes()) {
        Ok(()) => {
            sayln!("wrote {}", output.display());
            ExitCode::SUCCESS
        }
        Err(e) => bad_input(format!("{}: cannot write: {e}", output.display())),
    }
}

/// Whether writing `output` would replace the plan or rules file being compiled.
fn refuses_overwrite(output: &Path, plan: &Path, rules: Option<&Path>) -> bool {
    let inputs: Vec<&Path> = std::iter::once(plan).chain(rules).collect();
    petrel_actors::files::overwrites_an_input(output, &inputs).is_some()
}
