//! The store's suite, the same on SQLite and on PostgreSQL.

use super::*;

/// The test PostgreSQL's fresh schemas, shared with the integration tests.
#[path = "../../../tests/suite/harness/postgres.rs"]
mod postgres;

/// A fresh SQLite file, and a fresh PostgreSQL schema where one is reachable.
async fn stores() -> Vec<(&'static str, Store)> {
    let dir = std::env::temp_dir().join(format!("windmeta-store-{}", uuid::Uuid::new_v4().simple()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut stores =
        vec![("sqlite", Store::connect(&format!("sqlite://{}", dir.join("t.db").display())).await.unwrap())];
    if let Some(url) = postgres::fresh_postgres().await {
        stores.push(("postgres", Store::connect(&url).await.unwrap()));
    }
    stores
}

async fn queue(store: &Store, id: &str) {
    assert_eq!(store.insert_job(id, "calibration", "{}", None, 0, 100).await.unwrap(), Enqueued::New);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_job_runs_once_and_stores_its_metamodel() {
    for (name, store) in stores().await {
        queue(&store, "j1").await;
        let job = store.claim("w1", 10_000).await.unwrap().expect("a queued job is claimed");
        assert_eq!((job.id.as_str(), job.state.as_str(), job.attempts), ("j1", "running", 1), "{name}");
        assert!(store.claim("w2", 10_000).await.unwrap().is_none(), "{name}: claimed twice");
        assert_eq!(store.heartbeat("j1", "w1", 10_000, Some("{\"stage\":\"x\"}")).await.unwrap(), Some(false));
        assert!(store.complete("j1", "w1", "m1", "frame40", "{\"a\":1}").await.unwrap(), "{name}");
        let done = store.job("j1").await.unwrap().unwrap();
        assert_eq!((done.state.as_str(), done.metamodel_id.as_deref()), ("succeeded", Some("m1")), "{name}");
        assert_eq!(store.metamodel_body("m1").await.unwrap().as_deref(), Some("{\"a\":1}"), "{name}");
        assert_eq!(store.metamodels(10, 0).await.unwrap().len(), 1, "{name}");
        assert!(store.delete_metamodel("m1").await.unwrap() && !store.delete_metamodel("m1").await.unwrap());
    }
}

/// Many workers claiming at once from many connections: every job exactly once.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn concurrent_claims_hand_out_each_job_once() {
    for (name, store) in stores().await {
        for i in 0..20 {
            queue(&store, &format!("j{i:02}")).await;
        }
        let claimers = (0..8).map(|w| {
            let store = store.clone();
            tokio::spawn(async move {
                let mut mine = Vec::new();
                while let Some(job) = store.claim(&format!("w{w}"), 60_000).await.unwrap() {
                    mine.push(job.id);
                }
                mine
            })
        });
        let mut claimed: Vec<String> = Vec::new();
        for claimer in claimers.collect::<Vec<_>>() {
            claimed.extend(claimer.await.unwrap());
        }
        claimed.sort();
        let expected: Vec<String> = (0..20).map(|i| format!("j{i:02}")).collect();
        assert_eq!(claimed, expected, "{name}");
    }
}

/// A worker that lost its lease cannot complete: the job belongs to the one that took it up.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_lost_lease_discards_the_stale_result() {
    for (name, store) in stores().await {
        queue(&store, "j").await;
        store.claim("stale", 1).await.unwrap().unwrap();
        tokio::time::sleep(std::time::Duration::from_millis(5)).await;
        let again = store.claim("fresh", 60_000).await.unwrap().expect("an expired lease is taken up");
        assert_eq!(again.attempts, 2, "{name}");
        assert_eq!(store.heartbeat("j", "stale", 60_000, None).await.unwrap(), None, "{name}");
        assert!(!store.complete("j", "stale", "m-stale", "p", "{}").await.unwrap(), "{name}");
        assert!(!store.finish("j", "stale", "failed", Some("x"), None).await.unwrap(), "{name}");
        assert!(store.complete("j", "fresh", "m-fresh", "p", "{}").await.unwrap(), "{name}");
        let ids: Vec<String> = store.metamodels(10, 0).await.unwrap().into_iter().map(|m| m.id).collect();
        assert_eq!(ids, vec!["m-fresh".to_string()], "{name}: completed twice");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_job_whose_worker_keeps_dying_fails_with_the_reason() {
    for (name, store) in stores().await {
        queue(&store, "j").await;
        for attempt in 1..=MAX_ATTEMPTS {
            let job = store.claim("w", 1).await.unwrap().expect("taken up again");
            assert_eq!(job.attempts, attempt, "{name}");
            tokio::time::sleep(std::time::Duration::from_millis(5)).await;
        }
        assert!(store.claim("w", 1).await.unwrap().is_none(), "{name}: retried without bound");
        let job = store.job("j").await.unwrap().unwrap();
        assert_eq!(job.state, "failed", "{name}");
        assert!(job.error.unwrap().contains("3 times"), "{name}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancel_release_idempotency_and_a_full_queue() {
    for (name, store) in stores().await {
        queue(&store, "queued").await;
        let cancelled = store.request_cancel("queued").await.unwrap().unwrap();
        assert_eq!(cancelled.state, "cancelled", "{name}");
        queue(&store, "running").await;
        store.claim("w", 60_000).await.unwrap().unwrap();
        store.request_cancel("running").await.unwrap();
        assert_eq!(store.heartbeat("running", "w", 60_000, None).await.unwrap(), Some(true), "{name}");
        store.release("running", "w").await.unwrap();
        assert_eq!(store.job("running").await.unwrap().unwrap().state, "queued", "{name}");

        let key = Some(("k", "calibrations"));
        assert_eq!(store.insert_job("a", "calibration", "{}", key, 0, 100).await.unwrap(), Enqueued::New);
        let replay = store.insert_job("b", "calibration", "{}", key, 0, 100).await.unwrap();
        assert_eq!(replay, Enqueued::Earlier { id: "a".into(), request: "{}".into() }, "{name}");
        // Two queued now ("running" was released, "a"): a queue of two is full, a replay still answers.
        assert_eq!(store.insert_job("c", "calibration", "{}", None, 0, 2).await.unwrap(), Enqueued::QueueFull);
        assert!(matches!(
            store.insert_job("d", "calibration", "{}", key, 0, 2).await.unwrap(),
            Enqueued::Earlier { .. }
        ));
        assert!(store.job("c").await.unwrap().is_none() && store.ping().await, "{name}");
        // An expired key starts new work; pruning forgets the keys older than the cutoff.
        let later = now_ms() + 1;
        assert_eq!(store.insert_job("e", "calibration", "{}", key, later, 100).await.unwrap(), Enqueued::New);
        let other = Some(("k2", "calibrations"));
        assert_eq!(store.insert_job("f", "calibration", "{}", other, 0, 100).await.unwrap(), Enqueued::New);
        assert_eq!(store.prune_idempotency(now_ms() + 1).await.unwrap(), 2, "{name}");
    }
}

use tasks::TaskTally;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn tasks_of_a_running_job_are_shared_and_tallied() {
    for (name, store) in stores().await {
        queue(&store, "j").await;
        let requests = ["a".to_string(), "b".to_string()];
        store.insert_tasks("j", 0, &requests).await.unwrap();
        assert!(store.claim_task("w1", 60_000, None).await.unwrap().is_none(), "{name}: the job is not running");
        store.claim("coordinator", 60_000).await.unwrap().unwrap();
        let first = store.claim_task("w1", 60_000, None).await.unwrap().unwrap();
        let second = store.claim_task("w2", 60_000, Some("j")).await.unwrap().unwrap();
        assert_eq!((first.chunk, first.request.as_str(), second.chunk), (0, "a", 1), "{name}");
        assert!(store.claim_task("w3", 60_000, None).await.unwrap().is_none(), "{name}: handed out twice");
        assert_eq!(store.heartbeat_task("j", 0, "w1", 60_000).await.unwrap(), Some(true), "{name}");
        assert_eq!(store.heartbeat_task("j", 0, "w2", 60_000).await.unwrap(), None, "{name}: not w2's");
        assert!(!store.finish_task("j", 0, "w2", "done", "stolen").await.unwrap(), "{name}");
        assert!(store.finish_task("j", 0, "w1", "done", "r0").await.unwrap(), "{name}");
        assert!(store.finish_task("j", 1, "w2", "failed", "boom").await.unwrap(), "{name}");
        let tally = store.task_tally("j", 0..2).await.unwrap();
        assert_eq!(tally, TaskTally { total: 2, done: 1, failure: Some("boom".into()) }, "{name}");
        assert_eq!(store.task_results("j", 0..2).await.unwrap(), vec!["r0".to_string()], "{name}");
        // A second attempt at the job: an unchanged chunk keeps its output, a changed one restarts.
        store.insert_tasks("j", 0, &["a".to_string(), "b2".to_string()]).await.unwrap();
        assert_eq!(store.task_tally("j", 0..2).await.unwrap(), TaskTally { total: 2, done: 1, failure: None });
        // A later chunk (an earlier attempt's, say) is neither counted nor read with these.
        store.insert_tasks("j", 2, &["c".to_string()]).await.unwrap();
        assert_eq!(store.task_tally("j", 0..2).await.unwrap(), TaskTally { total: 2, done: 1, failure: None });
        assert_eq!(store.task_tally("j", 1..3).await.unwrap(), TaskTally { total: 2, done: 0, failure: None });
        // Cancelling the job withdraws its tasks from idle workers and from the one running them.
        let again = store.claim_task("w1", 60_000, None).await.unwrap().unwrap();
        store.request_cancel("j").await.unwrap();
        assert_eq!(store.heartbeat_task("j", again.chunk, "w1", 60_000).await.unwrap(), Some(false), "{name}");
        store.release_task("j", again.chunk, "w1").await.unwrap();
        assert!(store.claim_task("w1", 60_000, None).await.unwrap().is_none(), "{name}");
    }
}
