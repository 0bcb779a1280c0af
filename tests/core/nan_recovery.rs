//! An output that once was not a number (a NaN input) recovers as soon as its input does:
//! smoothing weighted even by 0 kept NaN forever.

use petrel::actors::DEFAULT_STOP_TIMEOUT;

use crate::support::{advance, start};

#[tokio::test(start_paused = true)]
async fn a_smoothed_scale_recovers_from_a_nan_input() {
    for smoothing in [0.0, 0.5] {
        let agent = start(&format!(
            r#"Agent(name: "r1", modules: [(name: "s", type: "demo.scale", values: {{"params/smoothing": {smoothing:?}}})])"#
        ))
        .await;
        let bb = agent.blackboard();
        let out = || async { *bb.get::<f64>("s/out/value").await.unwrap() };
        bb.set("s/in/value", f64::NAN).await.unwrap();
        advance(10).await;
        assert!(out().await.is_nan(), "smoothing {smoothing}");
        bb.set("s/in/value", 2.0).await.unwrap();
        advance(10).await;
        assert_eq!(
            out().await,
            2.0,
            "smoothing {smoothing}: starts over from the input"
        );
        bb.set("s/in/value", 4.0).await.unwrap();
        advance(10).await;
        assert_eq!(
            out().await,
            4.0 - 2.0 * smoothing,
            "smoothing {smoothing}: and smooths again"
        );
        agent.stop(DEFAULT_STOP_TIMEOUT).await;
    }
}
