//! `petrel get` and `petrel set`: read and write properties of running agents over their team.

use std::path::PathBuf;
use std::process::ExitCode;

use petrel_actors::{ConfigFile, PropertyUrl};
use petrel_team::{Client, TeamError};

use super::{bad_input, EXIT_BAD_INPUT};

/// Exit code when the agent refused or did not answer.
const EXIT_REFUSED: u8 = 1;

/// What to do once attached.
pub(crate) enum Request {
    Get,
    Set(String),
}

/// Attaches to the team that `via`'s `team:` section names and carries out `request` on `url`.
pub(crate) fn run(via: &PathBuf, url: &str, request: Request) -> ExitCode {
    let file = match ConfigFile::load(via) {
        Ok(f) => f,
        Err(e) => return bad_input(&e),
    };
    let Some(team) = file.config.team.clone() else {
        eprintln!(
            "error: {} has no `team:` section: give the config of an agent of the team to reach",
            via.display()
        );
        return ExitCode::from(EXIT_BAD_INPUT);
    };
    let url = match PropertyUrl::parse(url) {
        Ok(u) if u.agent().is_some() => u,
        Ok(_) => {
            eprintln!("error: `{url}` names no agent: write it `petrel://agent/module/path`");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let runtime = match tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("error: cannot start the async runtime: {e}");
            return ExitCode::FAILURE;
        }
    };
    runtime.block_on(async {
        let client = match Client::connect(&team).await {
            Ok(c) => c,
            Err(e) => return failed(e),
        };
        let result = match &request {
            Request::Get => client.get_json(&url).await.map(|(type_name, json)| {
                println!("{} ({type_name})", String::from_utf8_lossy(&json));
            }),
            Request::Set(value) => client.set_ron(&url, value).await.map(|()| {
                println!("{url} = {value}");
            }),
        };
        client.close().await;
        match result {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => failed(e),
        }
    })
}

fn failed(e: TeamError) -> ExitCode {
    eprintln!("error: {e}");
    ExitCode::from(EXIT_REFUSED)
}
