//! Times `GridMaxFlow::solve` on a GCG1 graph and, in the same run, the reference (Kolmogorov's
//! maxflow through PyMaxflow, run as a separate program).
//!
//! Usage: bench_maxflow FILE.gcg [--ref FLOW] [--reps N] [--peer-reps N] [--no-prepass]
//!        [--peer-python PY] [--peer-script maxflow_bench.py]
//! Peer paths default to $MAXFLOW_PEER_PY / $MAXFLOW_PEER_SCRIPT; the peer is skipped with a message
//! when they are not set or it fails. Run with OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1.

use std::path::Path;
use std::process::{Command, ExitCode};
use std::time::Instant;

use suitcap::segment::gcg::read_gcg;
use suitcap::segment::maxflow::GridMaxFlow;
use suitcap::stats::median;

/// Runs the peer and returns (median ms, flow) parsed from its output.
fn run_peer(py: &str, script: &str, file: &str, reps: usize) -> Result<(f64, f64, String), String> {
    let out = Command::new(py)
        .args([script, "solve", file, "--reps", &reps.to_string()])
        .env("OMP_NUM_THREADS", "1")
        .env("OPENBLAS_NUM_THREADS", "1")
        .output()
        .map_err(|e| format!("cannot run {py}: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    if !out.status.success() {
        return Err(format!(
            "peer failed: {}{}",
            text,
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let mut med = None;
    let mut flow = None;
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("maxflow     : median ") {
            med = rest
                .split_whitespace()
                .next()
                .and_then(|s| s.parse::<f64>().ok());
        }
        if let Some(rest) = line.strip_prefix("flow = ") {
            flow = rest.trim().parse::<f64>().ok();
        }
    }
    match (med, flow) {
        (Some(m), Some(f)) => Ok((m, f, text)),
        _ => Err(format!("cannot parse peer output:\n{text}")),
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut file = None;
    let mut reference: Option<f64> = None;
    let mut reps = 15usize;
    let mut peer_reps = 7usize;
    let mut prepass = true;
    let mut py = std::env::var("MAXFLOW_PEER_PY").ok();
    let mut script = std::env::var("MAXFLOW_PEER_SCRIPT").ok();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = |name: &str| {
            it.next()
                .cloned()
                .ok_or_else(|| format!("{name} needs a value"))
        };
        let r: Result<(), String> = (|| {
            match a.as_str() {
                "--ref" => {
                    reference = Some(val("--ref")?.parse().map_err(|e| format!("--ref: {e}"))?)
                }
                "--reps" => reps = val("--reps")?.parse().map_err(|e| format!("--reps: {e}"))?,
                "--peer-reps" => {
                    peer_reps = val("--peer-reps")?
                        .parse()
                        .map_err(|e| format!("--peer-reps: {e}"))?
                }
                "--peer-python" => py = Some(val("--peer-python")?),
                "--peer-script" => script = Some(val("--peer-script")?),
                "--no-prepass" => prepass = false,
                _ if file.is_none() => file = Some(a.clone()),
                _ => return Err(format!("unexpected argument {a}")),
            }
            Ok(())
        })();
        if let Err(e) = r {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    }
    let Some(file) = file else {
        eprintln!("usage: bench_maxflow FILE.gcg [--ref FLOW] [--reps N] [--peer-reps N] [--peer-python PY] [--peer-script S]");
        return ExitCode::from(2);
    };
    let g = match read_gcg(Path::new(&file)) {
        Ok(g) => g,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    let mut mf = GridMaxFlow::new();
    if !prepass {
        mf.set_prepass(false);
    }
    let mut times = Vec::with_capacity(reps);
    let mut phases: [Vec<f64>; 3] = Default::default();
    let mut result = mf.solve(&g); // warm-up (allocates buffers)
    for _ in 0..reps {
        let t = Instant::now();
        result = mf.solve(&g);
        times.push(t.elapsed().as_secs_f64() * 1e3);
        let p = mf.times();
        for (v, ms) in phases
            .iter_mut()
            .zip([p.prepare_ms, p.search_ms, p.labels_ms])
        {
            v.push(ms);
        }
    }
    println!("ours: {:?}", mf.stats());
    let [prepare, search, labels] = phases.map(|v| median(&v).unwrap_or(f64::NAN));
    println!(
        "ours: phases (medians) prepare {prepare:.2} ms, search {search:.2} ms, labels {labels:.2} ms"
    );
    let fg = result.labels.iter().filter(|&&l| l).count();
    let cut = g.cut_cost(&result.labels);
    let min = times.iter().cloned().fold(f64::INFINITY, f64::min);
    let med = median(&times).unwrap_or(f64::NAN);
    println!("file {file}: {}x{} (W x H)", g.width(), g.height());
    println!(
        "ours: flow = {:.6}  cut_cost_f64 = {:.6}  source_side_nodes = {fg}",
        result.flow, cut
    );
    println!("ours: solve median {med:.2} ms, min {min:.2} ms (n={reps}, prepass={prepass})");
    let mut ok = true;
    if let Some(r) = reference {
        let rel = (result.flow - r).abs() / r.abs().max(1.0);
        let relc = (cut - r).abs() / r.abs().max(1.0);
        let pass = rel <= 1e-5 && relc <= 1e-5;
        ok &= pass;
        println!(
            "check vs reference {r:.6}: flow rel err {rel:.2e}, cut rel err {relc:.2e} -> {}",
            if pass { "OK" } else { "FAIL" }
        );
    }
    match (py, script) {
        (Some(py), Some(script)) => match run_peer(&py, &script, &file, peer_reps) {
            Ok((pmed, pflow, _)) => {
                println!("peer (Kolmogorov maxflow via PyMaxflow): flow = {pflow:.6}, solve median {pmed:.2} ms (n={peer_reps})");
                println!("ratio peer/ours (median) = {:.2}x", pmed / med);
            }
            Err(e) => println!("peer skipped: {e}"),
        },
        _ => println!("peer skipped: set MAXFLOW_PEER_PY and MAXFLOW_PEER_SCRIPT (or --peer-python/--peer-script)"),
    }
    if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
