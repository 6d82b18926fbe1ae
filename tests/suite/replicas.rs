//! Several `windmeta serve` processes on one PostgreSQL database: they share the job queue and the
//! tasks of one job (a calibration's structure selection, experiments and expansions, an answer's
//! metamodel storms, a certified answer's reference storms), a
//! replica killed in the middle of a job loses it to another that finishes it, and no job completes
//! twice. Skipped, with the reason printed, where no PostgreSQL is reachable.

use crate::harness::fixture;
use crate::harness::postgres::fresh_postgres;
use serde_json::{Value, json};
use sqlx::Row;
use std::collections::{BTreeMap, BTreeSet};
use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};
use windmeta::analysis::{ExceedanceOptions, OnThisMachine, Response, metamodel_exceedance};
use windmeta::progress::Silent;

struct Replica {
    child: Child,
    address: String,
}

impl Replica {
    /// Starts the real binary and waits for the address it reports in its log.
    fn start(database_url: &str, role: &str) -> Replica {
        let mut child = Command::new(env!("CARGO_BIN_EXE_windmeta"))
            .arg("serve")
            .env("WINDMETA_LISTEN", "127.0.0.1:0")
            .env("DATABASE_URL", database_url)
            .env("WINDMETA_ROLE", role)
            .env("WINDMETA_WORKERS", "1")
            .env("WINDMETA_LEASE_MS", "3000")
            .env("NO_COLOR", "1")
            .env("RUST_LOG", "info")
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("the binary starts");
        let stdout = child.stdout.take().unwrap();
        let (found, address) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if let Some(rest) = line.split("address=").nth(1) {
                    let address: String =
                        rest.chars().take_while(|c| c.is_ascii_digit() || *c == '.' || *c == ':').collect();
                    let _ = found.send(address);
                }
            }
        });
        let address = address.recv_timeout(Duration::from_secs(60)).expect("the replica reports its address");
        Replica { child, address: format!("http://{address}") }
    }

    fn pid(&self) -> u32 {
        self.child.id()
    }
}

impl Drop for Replica {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

async fn operation(client: &reqwest::Client, replica: &Replica, id: &str) -> Value {
    client.get(format!("{}/v1/operations/{id}", replica.address)).send().await.unwrap().json().await.unwrap()
}

/// Polls the operation until it is done and asserts that it succeeded.
async fn wait_succeeded(client: &reqwest::Client, replica: &Replica, id: &str, limit: Duration) {
    let started = Instant::now();
    loop {
        let op = operation(client, replica, id).await;
        if op["done"] == true {
            assert_eq!(op["state"], "succeeded", "{op}");
            return;
        }
        assert!(started.elapsed() < limit, "stuck: {op}");
        tokio::time::sleep(Duration::from_millis(250)).await;
    }
}

/// The process id in a lease owner (`host-pidN-uuid`).
fn pid_of(owner: &str) -> String {
    owner.split("-pid").nth(1).and_then(|p| p.split('-').next()).unwrap().to_string()
}

/// (job id, lease owner) of the running jobs.
async fn running(pool: &sqlx::AnyPool) -> Vec<(String, String)> {
    let rows = sqlx::query("SELECT id, lease_owner FROM jobs WHERE state = 'running'").fetch_all(pool).await.unwrap();
    rows.iter().map(|r| (r.get("id"), r.get("lease_owner"))).collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn replicas_share_jobs_and_survive_a_killed_one() {
    let Some(url) = fresh_postgres().await else { return };
    let pool = sqlx::AnyPool::connect(&url).await.unwrap();
    let first = Replica::start(&url, "all");
    let second = Replica::start(&url, "all");
    let client = reqwest::Client::new();

    // Two calibrations posted to one replica: each replica (one worker each) runs one of them.
    let mut ids = Vec::new();
    for seed in [1, 2] {
        let body = json!({"experiments": 40, "duration_s": 300, "seed": seed});
        let r = client.post(format!("{}/v1/calibrations", first.address)).json(&body).send().await.unwrap();
        assert_eq!(r.status().as_u16(), 202);
        ids.push(r.json::<Value>().await.unwrap()["id"].as_str().unwrap().to_string());
    }
    let started = Instant::now();
    let owners = loop {
        let jobs = running(&pool).await;
        if jobs.len() == 2 {
            break jobs;
        }
        assert!(started.elapsed() < Duration::from_secs(60), "both jobs never ran at once: {jobs:?}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    };
    let mut pids: Vec<String> = owners.iter().map(|(_, owner)| pid_of(owner)).collect();
    pids.sort();
    let mut expected = vec![first.pid().to_string(), second.pid().to_string()];
    expected.sort();
    assert_eq!(pids, expected, "each replica runs one job");

    // Kill the first replica (no graceful release): its job's lease runs out and the second takes it up.
    let (orphan, _) = owners.iter().find(|(_, owner)| pid_of(owner) == first.pid().to_string()).unwrap().clone();
    drop(first);
    for id in &ids {
        wait_succeeded(&client, &second, id, Duration::from_secs(300)).await;
    }
    let orphan_op = operation(&client, &second, &orphan).await;
    assert_eq!(orphan_op["attempts"], 2, "taken up again once: {orphan_op}");
    for id in &ids {
        let stored: i64 = sqlx::query("SELECT COUNT(*) AS n FROM metamodels WHERE job_id = $1")
            .bind(id)
            .fetch_one(&pool)
            .await
            .unwrap()
            .get("n");
        assert_eq!(stored, 1, "job {id} completed {stored} times");
    }
}

/// An API-only replica queues work and serves it; a worker-only replica runs it and serves only
/// health and metrics.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn api_and_worker_roles_split_the_work() {
    let Some(url) = fresh_postgres().await else { return };
    let api = Replica::start(&url, "api");
    let client = reqwest::Client::new();
    let body = json!({"experiments": 8, "duration_s": 30, "seed": 3});
    let r = client.post(format!("{}/v1/calibrations", api.address)).json(&body).send().await.unwrap();
    let id = r.json::<Value>().await.unwrap()["id"].as_str().unwrap().to_string();
    tokio::time::sleep(Duration::from_millis(1500)).await;
    assert_eq!(operation(&client, &api, &id).await["state"], "queued", "an API replica runs nothing");
    let worker = Replica::start(&url, "worker");
    let health = client.get(format!("{}/readyz", worker.address)).send().await.unwrap();
    assert_eq!(health.status().as_u16(), 200);
    let v1 = client.get(format!("{}/v1/presets", worker.address)).send().await.unwrap();
    assert_eq!(v1.status().as_u16(), 404, "a worker replica serves no API");
    wait_succeeded(&client, &api, &id, Duration::from_secs(120)).await;
}

/// What a task's request asks for, told by a field only that kind of task has.
fn task_kind(request: &str) -> &'static str {
    let request: Value = serde_json::from_str(request).expect("a task's request is JSON");
    let kinds = [
        ("mode", "structure"),
        ("experiments", "experiments"),
        ("targets", "expansions"),
        ("order", "reference storms"),
        ("responses", "metamodel storms"),
    ];
    kinds.iter().find(|(field, _)| request.get(field).is_some()).map(|(_, kind)| *kind).expect("a known task")
}

/// Polls a job's tasks until the job is done and it succeeded: its operation, and per kind of
/// task the replicas (process ids) that ran one.
async fn watch_tasks(
    pool: &sqlx::AnyPool,
    client: &reqwest::Client,
    replica: &Replica,
    id: &str,
) -> (Value, BTreeMap<&'static str, BTreeSet<String>>) {
    let mut runners: BTreeMap<&'static str, BTreeSet<String>> = BTreeMap::new();
    let started = Instant::now();
    loop {
        let rows = sqlx::query("SELECT request, lease_owner FROM tasks WHERE job_id = $1 AND lease_owner IS NOT NULL")
            .bind(id)
            .fetch_all(pool)
            .await
            .unwrap();
        for row in rows {
            let (request, owner): (String, String) = (row.get("request"), row.get("lease_owner"));
            runners.entry(task_kind(&request)).or_default().insert(pid_of(&owner));
        }
        let op = operation(client, replica, id).await;
        if op["done"] == true {
            assert_eq!(op["state"], "succeeded", "{op}");
            return (op, runners);
        }
        assert!(started.elapsed() < Duration::from_secs(300), "stuck: {op}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

/// One calibration is spread over the replicas: its structure selection, experiments and
/// expansions run as tasks, and both replicas run experiments of it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn one_calibration_is_spread_over_replicas() {
    let Some(url) = fresh_postgres().await else { return };
    let pool = sqlx::AnyPool::connect(&url).await.unwrap();
    let first = Replica::start(&url, "all");
    let second = Replica::start(&url, "all");
    let client = reqwest::Client::new();
    let body = json!({"experiments": 100, "duration_s": 300, "seed": 4});
    let r = client.post(format!("{}/v1/calibrations", first.address)).json(&body).send().await.unwrap();
    let id = r.json::<Value>().await.unwrap()["id"].as_str().unwrap().to_string();
    let (_, runners) = watch_tasks(&pool, &client, &second, &id).await;
    let kinds: Vec<&str> = runners.keys().copied().collect();
    assert_eq!(kinds, ["expansions", "experiments", "structure"], "{runners:?}");
    let both: BTreeSet<String> = [first.pid().to_string(), second.pid().to_string()].into();
    assert_eq!(runners["experiments"], both, "both replicas ran experiments of the one calibration");
}

/// An answer's metamodel storms are shared by the replicas in tasks, and the answer is the one
/// computed in this process, to the bit: a storm's peaks depend only on its row and its stream.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn metamodel_storms_are_shared_and_answer_as_in_process() {
    let Some(url) = fresh_postgres().await else { return };
    let pool = sqlx::AnyPool::connect(&url).await.unwrap();
    let first = Replica::start(&url, "all");
    let second = Replica::start(&url, "all");
    let metamodel_id = fixture::install_at(&url, 900.0).await;
    let client = reqwest::Client::new();
    // Six tasks of storms (more than one task's worth, which an answer runs where it is).
    let body = json!({"samples": 6000, "seed": 6, "response": "acceleration", "floor": 30});
    let path = format!("{}/v1/metamodels/{metamodel_id}/exceedance", first.address);
    let r = client.post(path).json(&body).send().await.unwrap();
    assert_eq!(r.status().as_u16(), 202);
    let id = r.json::<Value>().await.unwrap()["id"].as_str().unwrap().to_string();
    let (op, runners) = watch_tasks(&pool, &client, &second, &id).await;
    let both: BTreeSet<String> = [first.pid().to_string(), second.pid().to_string()].into();
    assert_eq!(runners.get("metamodel storms"), Some(&both), "both replicas ran storms: {runners:?}");

    let mut metamodel = fixture::metamodel().0.clone();
    metamodel.study.duration_s = Some(900.0);
    let options = ExceedanceOptions {
        samples: 6000,
        seed: 6,
        fixed: Default::default(),
        thresholds: None,
        confidence: 0.95,
        profile_quantile: None,
        certify: None,
    };
    let in_process = tokio::task::block_in_place(|| {
        let study = metamodel.study().unwrap();
        let response = Response::Acceleration { floor: 30 };
        metamodel_exceedance(&metamodel, &study, response, &options, &OnThisMachine, &Silent).unwrap()
    });
    let curve = serde_json::to_value(&in_process.curve).unwrap();
    for (field, value) in curve.as_object().unwrap() {
        assert_eq!(&op["result"][field], value, "{field}");
    }
}

/// (chunk, state, attempts, lease owner's process id) of a job's tasks.
async fn tasks_of(pool: &sqlx::AnyPool, job: &str) -> Vec<(i64, String, i64, Option<String>)> {
    let rows = sqlx::query("SELECT chunk, state, attempts, lease_owner FROM tasks WHERE job_id = $1 ORDER BY chunk")
        .bind(job)
        .fetch_all(pool)
        .await
        .unwrap();
    let owner = |r: &sqlx::any::AnyRow| r.get::<Option<String>, _>("lease_owner").map(|o| pid_of(&o));
    rows.iter().map(|r| (r.get("chunk"), r.get("state"), r.get("attempts"), owner(r))).collect()
}

/// A certified curve's reference storms are shared by both replicas; the replica that runs the
/// job is killed midway, and the other takes the job up, keeps the reference storms done before
/// (not run again) and finishes the answer.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn reference_storms_are_shared_by_replicas_and_survive_a_killed_one() {
    let Some(url) = fresh_postgres().await else { return };
    let pool = sqlx::AnyPool::connect(&url).await.unwrap();
    let mut replicas = vec![Replica::start(&url, "all"), Replica::start(&url, "all")];
    // Full-length storms: a reference storm takes a quarter of a second of one core.
    let metamodel = fixture::install_at(&url, 900.0).await;
    let client = reqwest::Client::new();
    let body = json!({"samples": 400, "seed": 5, "response": "acceleration", "certify": {"reference_storms": 120}});
    let path = format!("{}/v1/metamodels/{metamodel}/exceedance", replicas[0].address);
    let r = client.post(path).json(&body).send().await.unwrap();
    assert_eq!(r.status().as_u16(), 202);
    let id = r.json::<Value>().await.unwrap()["id"].as_str().unwrap().to_string();

    // Until both replicas have run reference storms and some are done.
    let mut task_owners = std::collections::BTreeSet::new();
    let started = Instant::now();
    let (coordinator, done_before) = loop {
        let tasks = tasks_of(&pool, &id).await;
        task_owners.extend(tasks.iter().filter(|t| t.1 == "running").filter_map(|t| t.3.clone()));
        let done: Vec<(i64, i64)> = tasks.iter().filter(|t| t.1 == "done").map(|t| (t.0, t.2)).collect();
        let job = running(&pool).await.into_iter().find(|(job, _)| *job == id);
        if let Some((_, owner)) = job
            && task_owners.len() == 2
            && done.len() >= 2
            && done.len() + 3 < tasks.len()
        {
            break (pid_of(&owner), done);
        }
        assert!(started.elapsed() < Duration::from_secs(120), "the tasks were never shared: {tasks:?}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    };
    let mut expected = std::collections::BTreeSet::new();
    expected.extend(replicas.iter().map(|r| r.pid().to_string()));
    assert_eq!(task_owners, expected, "both replicas ran reference storms of the one answer");

    // Kill the job's replica: the survivor finishes its tasks and takes the job up.
    let killed = replicas.iter().position(|r| r.pid().to_string() == coordinator).unwrap();
    drop(replicas.remove(killed));
    let survivor = &replicas[0];
    let started = Instant::now();
    let op = loop {
        for (chunk, attempts) in &done_before {
            let now = tasks_of(&pool, &id).await.into_iter().find(|t| t.0 == *chunk);
            if let Some((_, state, again, _)) = now {
                assert_eq!((state.as_str(), again), ("done", *attempts), "chunk {chunk} was run again");
            }
        }
        let op = operation(&client, survivor, &id).await;
        if op["done"] == true {
            break op;
        }
        assert!(started.elapsed() < Duration::from_secs(300), "stuck: {op}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    };
    assert_eq!(op["state"], "succeeded", "{op}");
    assert_eq!(op["attempts"], 2, "taken up again once: {op}");
    let certification = &op["result"]["certification"];
    assert_eq!(certification["reference_storms"], 120, "{op}");
    let probabilities = op["result"]["probabilities"].as_array().unwrap();
    assert_eq!(certification["correction"].as_array().unwrap().len(), probabilities.len());
}
