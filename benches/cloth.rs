//! Cloth simulation speed and quality on real CMU motion: `cargo bench --bench cloth`.
//!
//! A T-shirt and a dress at about 2,000 and 4,000 vertices (the edge length chosen to give that
//! count) on the walk (02_01) and the kick (10_03) from `tests/data/mocap/`, subject "chidi",
//! resampled to 30 frames/s, the live settings (40 substeps × 6 Chebyshev-accelerated stretch sweeps; the issue asks for
//! its speed at 16 substeps, so these figures are stricter), one thread. Each case is dressed once outside the
//! timing; criterion then times simulating the whole clip from that state and reports frames/s as
//! its throughput. Before timing, each case prints its quality summary (edge strain, penetration;
//! the dressed first frame included) from `suitcap::cloth::solver::run_motion`; so does, untimed,
//! the quality mode of `suitcap run` and `drape` (80 substeps, 1 cm edges) for each clip and
//! garment, and the skirt (live at both sizes and quality mode; untimed). Targets (issue 6): 4,000 vertices ≥ 60 frames/s, 2,000 ≥ 120; strain p95 ≤ 2 %,
//! max ≤ 10 %; no vertex deeper than 2 mm in a capsule; no tunnelling at 3 m/s hand speed (each
//! clip's fastest hands and feet are printed, and the quality runs count the vertices that tunnel
//! through a capsule in any substep, `Cloth::check_tunnelling`; the frames/s in those lines include
//! the count's cost, criterion's throughput does not). `CLOTH_BENCH_SPEED_ONLY=1` skips the
//! quality figures (for timing runs that alternate builds). The T-shirt at 4,000 vertices is also
//! timed as `live` runs it on estimated poses (`…/estimated-inertia`: the cloth carried with its
//! bone every substep, [`SolverSettings::inertia`]); its quality figures are not printed (the
//! targets are for true motion, simulated at full inertia).

use std::path::Path;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};

use suitcap::body::Subject;
use suitcap::bvh::{Motion, CMU_CALIBRATION_FRAMES};
use suitcap::cloth::garment::{GarmentKind, GarmentMesh, GarmentParams};
use suitcap::cloth::material::Material;
use suitcap::cloth::proxies::{BodyRig, DEFAULT_MARGIN_CM};
use suitcap::cloth::solver::{run_motion, Cloth, SolverSettings};

fn bench(c: &mut Criterion) {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let subject = Subject::find("chidi").expect("subject");
    let clips = [
        ("walk", "tests/data/mocap/cmu_02_01_walk.bvh"),
        ("kick", "tests/data/mocap/cmu_10_03_kick_ball.bvh"),
    ];
    let settings = SolverSettings::live();
    let speed_only = std::env::var("CLOTH_BENCH_SPEED_ONLY").is_ok_and(|v| v == "1");
    let material = Material::medium();
    let mut group = c.benchmark_group("cloth");
    group.sample_size(10);
    group.warm_up_time(std::time::Duration::from_secs(1));
    group.measurement_time(std::time::Duration::from_secs(6));
    for (clip_name, clip) in clips {
        let motion = Motion::load(&repo.join(clip)).expect("clip");
        let rig = BodyRig::for_subject(subject, &motion.skeleton, DEFAULT_MARGIN_CM).expect("rig");
        let (frames, _) = rig
            .scale_motion(&motion)
            .resample(CMU_CALIBRATION_FRAMES, None, settings.fps as f64)
            .expect("resample");
        if !speed_only {
            let (hands, feet) = suitcap::cloth::solver::peak_limb_speeds(&frames);
            println!(
                "{clip_name}: hands up to {hands:.1} m/s, feet up to {feet:.1} m/s between frames"
            );
        }
        // Quality figures: the dressed garment run over the clip, its summary printed
        // (CLOTH_BENCH_SPEED_ONLY=1 leaves them out, for timing runs).
        let report = |label: String, mesh: &GarmentMesh, settings: &SolverSettings| {
            if speed_only {
                return;
            }
            let mut cloth = Cloth::new(mesh, &material, settings, &rig).expect("cloth");
            cloth.check_tunnelling(true);
            let summary = run_motion(&rig, &mut cloth, &frames, |_, _, _| {}).expect("simulate");
            println!("{clip_name}, {label}: {summary}");
        };
        for target in [2000usize, 4000] {
            let (mesh, edge) =
                GarmentMesh::with_vertex_count(GarmentKind::Skirt, &rig, target, 2.5)
                    .expect("garment");
            report(format!("{edge:.2} cm edges (untimed)"), &mesh, &settings);
        }
        let quality = SolverSettings::quality();
        for kind in [GarmentKind::TShirt, GarmentKind::Dress, GarmentKind::Skirt] {
            let mesh =
                GarmentMesh::generate(kind, &rig, &GarmentParams::quality()).expect("garment");
            let label = format!("quality mode ({} substeps, 1 cm edges)", quality.substeps);
            report(label, &mesh, &quality);
        }
        // The T-shirt at 4,000 vertices also as `live` runs it on estimated poses
        // (`suitcap::tryon::ESTIMATED_POSE_INERTIA`): what carrying the cloth with its bone every
        // substep costs.
        let live_app = SolverSettings {
            inertia: suitcap::tryon::ESTIMATED_POSE_INERTIA,
            ..settings.clone()
        };
        let cases = [
            (GarmentKind::TShirt, 2000usize, &settings, ""),
            (GarmentKind::TShirt, 4000, &settings, ""),
            (GarmentKind::TShirt, 4000, &live_app, "/estimated-inertia"),
            (GarmentKind::Dress, 2000, &settings, ""),
            (GarmentKind::Dress, 4000, &settings, ""),
        ];
        for (kind, target, settings, suffix) in cases {
            let (mesh, edge) =
                GarmentMesh::with_vertex_count(kind, &rig, target, 2.5).expect("garment");
            if suffix.is_empty() {
                report(format!("{edge:.2} cm edges"), &mesh, settings);
            }
            let mut dressed = Cloth::new(&mesh, &material, settings, &rig).expect("cloth");
            dressed.dress(&rig, frames.frame(0));
            let steps = frames.frame_count() - 1;
            group.throughput(Throughput::Elements(steps as u64));
            group.bench_function(
                format!(
                    "{clip_name}/{}/{}v{suffix}",
                    kind.name(),
                    mesh.positions.len()
                ),
                |b| {
                    b.iter_batched(
                        || dressed.clone(),
                        |mut cloth| {
                            for k in 1..frames.frame_count() {
                                cloth.step_frame(&rig, frames.frame(k - 1), frames.frame(k));
                            }
                            cloth
                        },
                        BatchSize::LargeInput,
                    )
                },
            );
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
