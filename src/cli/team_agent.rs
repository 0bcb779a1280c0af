//! The console's view of an agent reached over its team (`petrel console`): petrel-console's
//! `RemoteAgent` over the team `Client` the CLI tools use, so the console lists, reads,
//! follows and sets with the requests (and the owner's checks) of `petrel ls`, `top`, `echo`
//! and `set`.

use std::sync::Arc;

use petrel_actors::{AgentListing, FilePath, ModuleListing, PropertyUrl};
use petrel_console::source::BoxFuture;
use petrel_console::{PlanGraph, RemoteAgent, RemoteEvent, RemoteSample, RemoteWatch};
use petrel_team::{Client, Watch, WatchEvent};

/// One agent of a team, through a client shared with the other agents of that team.
pub(crate) struct TeamAgent {
    pub client: Arc<Client>,
    pub agent: String,
}

impl TeamAgent {
    fn url(&self, key: &str) -> Result<PropertyUrl, String> {
        PropertyUrl::parse(&format!("petrel://{}/{key}", self.agent)).map_err(|e| e.to_string())
    }

    /// The plans its `mission.pnp` modules run, read from the files their parameters name
    /// (the agent runs on this machine: its paths are ours).
    pub(crate) async fn plans(&self, listing: &AgentListing) -> Vec<PlanGraph> {
        let mut files = Vec::new();
        for m in listing
            .modules
            .iter()
            .filter(|m| m.type_name == "mission.pnp")
        {
            let path = |p: &str| {
                let key = format!("{}/params/{p}", m.name);
                async move {
                    let (_, json) = self.client.get_json(&self.url(&key).ok()?).await.ok()?;
                    serde_json::from_slice::<FilePath>(&json).ok()
                }
            };
            if let Some(plan) = path("plan").await {
                files.push((m.name.clone(), plan, path("rules").await));
            }
        }
        super::console::plans_from(files)
    }
}

impl RemoteAgent for TeamAgent {
    fn listing(&self) -> BoxFuture<'_, Result<AgentListing, String>> {
        Box::pin(async move {
            let info = self
                .client
                .info(&self.agent)
                .await
                .map_err(|e| e.to_string())?;
            let modules = info
                .modules
                .iter()
                .map(|m| ModuleListing {
                    name: m.clone(),
                    type_name: info.types.get(m).cloned().unwrap_or_default(),
                })
                .collect();
            Ok(AgentListing {
                modules,
                properties: info.properties,
            })
        })
    }

    fn get_matching<'a>(
        &'a self,
        pattern: &'a str,
    ) -> BoxFuture<'a, Result<Vec<(String, RemoteSample)>, String>> {
        Box::pin(async move {
            let values = self
                .client
                .get_matching(&self.agent, pattern)
                .await
                .map_err(|e| e.to_string())?;
            Ok(values
                .into_iter()
                .map(|(key, type_name, json)| {
                    (
                        key,
                        RemoteSample {
                            seq: 0,
                            type_name,
                            json,
                        },
                    )
                })
                .collect())
        })
    }

    fn set_ron<'a>(&'a self, key: &'a str, ron_text: &'a str) -> BoxFuture<'a, Result<(), String>> {
        Box::pin(async move {
            let url = self.url(key)?;
            self.client
                .set_ron(&url, ron_text)
                .await
                .map_err(|e| e.to_string())
        })
    }

    fn watch<'a>(&'a self, key: &'a str) -> BoxFuture<'a, Result<Box<dyn RemoteWatch>, String>> {
        Box::pin(async move {
            let url = self.url(key)?;
            let watch = self.client.watch(&url).await.map_err(|e| e.to_string())?;
            Ok(Box::new(Followed(watch)) as Box<dyn RemoteWatch>)
        })
    }
}

/// A property followed as `petrel echo` follows it.
struct Followed(Watch);

impl RemoteWatch for Followed {
    fn next(&mut self) -> BoxFuture<'_, Option<RemoteEvent>> {
        Box::pin(async move {
            Some(match self.0.next().await? {
                WatchEvent::Opened => RemoteEvent::Opened,
                WatchEvent::Update(u) => RemoteEvent::Sample(RemoteSample {
                    seq: u.seq,
                    type_name: u.type_name,
                    json: u.json,
                }),
                WatchEvent::Refused(why) => RemoteEvent::Refused(why),
            })
        })
    }
}
