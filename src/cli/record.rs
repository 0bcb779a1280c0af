//! `petrel run --record`, `petrel record info` and `petrel replay`: the command-line side of
//! the `petrel-record` crate.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::ValueEnum;
use petrel_actors::{ConfigFile, ModuleConfig};
use petrel_record::info::Info;
use petrel_record::{ChunkCompression, Format, RecordOptions, Recorder, Recording};

use super::EXIT_BAD_INPUT;

/// `--record-format`.
#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum RecordFormat {
    /// Foxglove schemas: grids, scans, poses and images as protobuf, the rest as JSON.
    Foxglove,
    /// Foxglove schemas, all as JSON (base64 cells and pixels): more CPU, larger files.
    FoxgloveJson,
    /// ROS 2 messages (ros2msg schemas, CDR), as rosbag2 writes them.
    Ros2,
}

impl From<RecordFormat> for Format {
    fn from(f: RecordFormat) -> Self {
        match f {
            RecordFormat::Foxglove => Format::Foxglove,
            RecordFormat::FoxgloveJson => Format::FoxgloveJson,
            RecordFormat::Ros2 => Format::Ros2,
        }
    }
}

/// `--record-compression`.
#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum RecordCompression {
    /// zstd level 1 (default): the least CPU on the robot and the smallest files.
    Zstd,
    /// LZ4: faster for readers to decompress, more CPU to write, larger files.
    Lz4,
}

impl From<RecordCompression> for ChunkCompression {
    fn from(c: RecordCompression) -> Self {
        match c {
            RecordCompression::Zstd => ChunkCompression::Zstd,
            RecordCompression::Lz4 => ChunkCompression::Lz4,
        }
    }
}

/// What `petrel replay` adds to a run.
#[derive(Clone)]
pub(crate) struct ReplaySpec {
    pub file: PathBuf,
    pub replace: Vec<String>,
    pub rate: f64,
    pub salvage: bool,
}

/// The name of the playback module `petrel replay` adds.
const REPLAY_MODULE: &str = "replay";

/// `--rate 2` or `--rate max` (0 for the module's parameter).
pub(crate) fn parse_rate(text: &str) -> Result<f64, String> {
    if text == "max" {
        return Ok(0.0);
    }
    let rate: f64 = text
        .parse()
        .map_err(|_| format!("expected a factor (e.g. 2) or `max`, got `{text}`"))?;
    // 0 is how the module's parameter says `max`; on the command line it is a typo, not a rate.
    (rate != 0.0)
        .then_some(())
        .ok_or_else(|| format!("expected a factor in [0.001, 1000] or `max`, got `{text}`"))?;
    petrel_record::replay::Rate::from_param(rate)
        .map_err(|_| format!("expected a factor in [0.001, 1000] or `max`, got `{text}`"))?;
    Ok(rate)
}

/// Turns `replace`d modules off and adds the playback module that writes their outputs; an
/// error names a `--replace` that is not a module of the config (which would run live, not
/// be replayed) and a module already called like the playback module.
pub(crate) fn apply_replay(file: &mut ConfigFile, spec: &ReplaySpec) -> Result<(), String> {
    let names: Vec<&str> = file
        .config
        .modules
        .iter()
        .map(|m| m.name.as_str())
        .collect();
    let config = file.path().display().to_string();
    if names.contains(&REPLAY_MODULE) {
        return Err(format!(
            "{config}: has a module named `{REPLAY_MODULE}`, the name of the playback module `petrel replay` adds; rename it to replay this config"
        ));
    }
    let twice = spec
        .replace
        .iter()
        .enumerate()
        .find(|(i, r)| spec.replace[..*i].contains(r));
    if let Some((_, twice)) = twice {
        return Err(format!(
            "--replace names `{twice}` twice; expected each module to replace once"
        ));
    }
    if let Some(missing) = spec.replace.iter().find(|r| !names.contains(&r.as_str())) {
        return Err(format!(
            "--replace {missing}: {config} has no module `{missing}`; expected one of its modules: {}",
            names.join(", ")
        ));
    }
    let path = std::path::absolute(&spec.file).unwrap_or_else(|_| spec.file.clone());
    for m in file
        .config
        .modules
        .iter_mut()
        .filter(|m| spec.replace.contains(&m.name))
    {
        m.values.insert("enabled".into(), ron::Value::Bool(false));
    }
    let value = |s: &str| ron::Value::String(s.to_string());
    file.config.modules.push(ModuleConfig {
        name: REPLAY_MODULE.into(),
        type_name: "record.replay".into(),
        values: [
            ("params/file".to_string(), value(&path.to_string_lossy())),
            ("params/modules".to_string(), value(&spec.replace.join(","))),
            (
                "params/rate".to_string(),
                ron::Value::Number(spec.rate.into()),
            ),
            ("params/salvage".to_string(), ron::Value::Bool(spec.salvage)),
            ("params/stop_at_end".to_string(), ron::Value::Bool(true)),
        ]
        .into(),
        ..Default::default()
    });
    Ok(())
}

/// The recording a run asks for: `--record FILE`, else the first config's `record:` section;
/// refused where it would overwrite one of `inputs`, the files the run uses.
pub(crate) fn options(
    file: Option<&PathBuf>,
    format: Option<RecordFormat>,
    compression: Option<RecordCompression>,
    configs: &[ConfigFile],
    inputs: &[&std::path::Path],
) -> Result<Option<RecordOptions>, ExitCode> {
    let section = configs.iter().find_map(|c| c.config.record.clone());
    if file.is_none() && section.is_none() {
        return Ok(None);
    }
    let section = section.unwrap_or_default();
    let (path, format) = (file.map(PathBuf::as_path), format.map(Into::into));
    RecordOptions::from_section(&section, path, format, compression.map(Into::into))
        .and_then(
            |options| match petrel_record::target::target_problem(&options.path, inputs) {
                Some(problem) => Err(format!("record: file: {problem}")),
                None => Ok(options),
            },
        )
        .map(Some)
        .map_err(|e| {
            eprintln!("error: {e}");
            ExitCode::from(EXIT_BAD_INPUT)
        })
}

/// Creates the recording (and records the log, if asked); agents are attached as they start.
pub(crate) fn start(options: RecordOptions) -> Result<Recorder, ExitCode> {
    let path = options.path.clone();
    let log = options.log;
    // The path is the user's: one the file cannot be made at is bad input.
    let mut recorder = Recorder::start(options).map_err(|e| {
        eprintln!("error: cannot record to {}: {e}", path.display());
        ExitCode::from(EXIT_BAD_INPUT)
    })?;
    if log {
        super::record_log::install(Some(recorder.log_sink()));
    }
    Ok(recorder)
}

/// Records agent `name` from before its modules start (and the modules added to it later).
pub(crate) async fn attach(
    recorder: &mut Recorder,
    name: &str,
    blackboard: &petrel_actors::Blackboard,
) -> Result<(), ExitCode> {
    match recorder.attach(name, blackboard).await {
        Ok(n) => {
            let file = recorder.options().path.display();
            tracing::info!(agent = name, properties = n, %file, "recording");
            Ok(())
        }
        Err(e) => {
            eprintln!("error: cannot record agent `{name}`: {e}");
            Err(ExitCode::FAILURE)
        }
    }
}

/// Ends the recording of a run that did not start, and removes its files.
pub(crate) async fn discard(recorder: Recorder) {
    super::record_log::install(None);
    if let Ok(report) = recorder.finish().await {
        for file in report.files {
            let _ = std::fs::remove_file(file);
        }
    }
}

/// Finishes the file and says what it holds.
pub(crate) async fn finish(recorder: Recorder) -> Result<(), String> {
    super::record_log::install(None);
    let report = recorder
        .finish()
        .await
        .map_err(|e| format!("the recording failed: {e}"))?;
    let files: Vec<String> = report
        .files
        .iter()
        .map(|f| f.display().to_string())
        .collect();
    petrel_actors::outln!(
        "recorded {} messages on {} channels to {} (dropped {}{})",
        report.written,
        report.channels,
        files.join(", "),
        report.dropped,
        match report.failed {
            0 => String::new(),
            n => format!(", {n} values could not be encoded"),
        }
    );
    Ok(())
}

/// `petrel record info FILE`.
pub(crate) fn info(file: &std::path::Path, salvage: bool) -> ExitCode {
    match Recording::open(file, salvage) {
        Ok(rec) => {
            super::stdout::say!("file:      {}\n{}", file.display(), Info::of(&rec));
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(EXIT_BAD_INPUT)
        }
    }
}
