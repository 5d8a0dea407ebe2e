//! Debug aid for the marker detector: why counted truth markers are missed and what the false
//! detections are, over generated datasets.
//!
//! `cargo run --release --example marker_misses -- MASKS_DIR_NAME DATASET [DATASET ...]`
//! (MASKS_DIR_NAME: `masks` for ground truth, `segmasks` for the segmenter's). Prints per dataset
//! the recall (the count) and precision, as `suitcap describe --truth-markers` scores
//! them, why each missed marker was missed (its detection taken by another truth marker of its
//! colour, on the same body part or another, or else the verdict of the nearest same-colour
//! component), and a few traits of the false detections.
//! `VERBOSE=1` lists every miss (with its marker id and the id of the truth marker that took its
//! detection, if one did) and every false detection; `DUMP=FILE` appends one CSV row per detection
//! (dataset, masks, frame, colour, area, border inside / cloth / outside, peak saturation, border
//! running on past the mask, correct, tolerance, x, y, whether the truth marker it was paired with
//! counts for recall, brightest value, summed value of the cloth on its border) for looking at the
//! tests' statistics.
use std::collections::BTreeMap;
use std::path::Path;

use suitcap::descriptor::markers::{
    match_tolerance, matched_detections, pair_markers, Component, DetectedMarker, MarkerDetector,
    TruthMarker, Verdict, COUNTED_VISIBLE_FRACTION,
};
use suitcap::mask::Mask;
use suitcap::suit::SuitDefinition;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    anyhow::ensure!(args.len() >= 3, "usage: MASKS_DIR_NAME DATASET...");
    let suit = SuitDefinition::load_dir(Path::new("suits/default"))?;
    let mut detector = MarkerDetector::new(&suit);
    let verbose = std::env::var("VERBOSE").is_ok();
    for data in &args[2..] {
        let data = Path::new(data);
        let text = std::fs::read_to_string(data.join("markers.csv"))?;
        let truth = suitcap::dataset::markers_from_csv(&text, &data.join("markers.csv"))?;
        let mut frames: Vec<_> = std::fs::read_dir(data.join("frames"))?
            .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
            .collect();
        frames.sort();
        let (mut counted, mut found, mut detections, mut correct) = (0, 0, 0, 0);
        let mut miss_reasons: BTreeMap<String, usize> = BTreeMap::new();
        let mut false_kinds: BTreeMap<String, usize> = BTreeMap::new();
        for name in &frames {
            let index: usize = name.trim_end_matches(".png").parse()?;
            let img = image::open(data.join("frames").join(name))?.to_rgb8();
            let mask = Mask::from_gray(&image::open(data.join(&args[1]).join(name))?.to_luma8());
            let comps = detector.components(&img, &mask);
            let expected = TruthMarker::of_frame(&truth, index, &suit);
            let tol = match_tolerance(&expected);
            let dets: Vec<&Component> = comps
                .iter()
                .filter(|c| c.verdict == Verdict::Marker)
                .collect();
            let detected: Vec<DetectedMarker> = dets.iter().map(|c| c.marker).collect();
            let paired = pair_markers(&detected, &expected, tol);
            let dm = matched_detections(&paired, detected.len());
            let counts = |m: &TruthMarker| m.counts(COUNTED_VISIBLE_FRACTION, 0);
            detections += dets.len();
            correct += dm.iter().filter(|&&m| m).count();
            for (t, e) in expected.iter().enumerate() {
                if !counts(e) {
                    continue;
                }
                counted += 1;
                if paired[t].is_some() {
                    found += 1;
                    continue;
                }
                let near = comps
                    .iter()
                    .filter(|c| c.marker.colour == e.colour)
                    .min_by(|a, b| {
                        a.marker
                            .centre
                            .distance(e.centre)
                            .total_cmp(&b.marker.centre.distance(e.centre))
                    });
                // A detection within tolerance that another truth marker of its colour took.
                let taken_by = paired.iter().enumerate().find_map(|(other, d)| {
                    d.filter(|&d| {
                        detected[d].colour == e.colour
                            && detected[d].centre.distance(e.centre) <= tol
                    })
                    .map(|_| other)
                });
                let reason = match (taken_by, near) {
                    (Some(other), _) => {
                        let whose = if !counts(&expected[other]) {
                            "a partly visible marker"
                        } else if expected[other].marker_id / 10_000 == e.marker_id / 10_000 {
                            "a counted marker of its part"
                        } else {
                            "a counted marker of another part"
                        };
                        format!("detection taken by {whose}")
                    }
                    (None, None) => "no component".to_string(),
                    (None, Some(c)) if c.marker.centre.distance(e.centre) > 2.0 * tol => {
                        "no component within 2 tol".to_string()
                    }
                    (None, Some(c)) => {
                        let far = c.marker.centre.distance(e.centre) > tol;
                        format!("{:?}{}", c.verdict, if far { " (off centre)" } else { "" })
                    }
                };
                if verbose {
                    let nearest = near.map(|c| (c.marker, c.border, c.peak_saturation));
                    let by = taken_by.map(|other| expected[other].marker_id);
                    println!(
                        "miss f{index} m{} {:?} c{} vis {:.2}/{} tol {tol:.1}: {reason} (by {by:?}) {nearest:?}",
                        e.marker_id, e.centre, e.colour, e.visible_fraction, e.visible_px
                    );
                }
                *miss_reasons.entry(reason).or_default() += 1;
            }
            // Per detection: whether the truth marker it was paired with counts for recall.
            let mut counted_match = vec![false; dets.len()];
            for (t, d) in paired.iter().enumerate() {
                if let Some(d) = *d {
                    counted_match[d] = counts(&expected[t]);
                }
            }
            if let Ok(path) = std::env::var("DUMP") {
                use std::io::Write;
                let mut out = std::fs::OpenOptions::new()
                    .append(true)
                    .create(true)
                    .open(path)?;
                for (d, c) in dets.iter().enumerate() {
                    writeln!(
                        out,
                        "{},{},{index},{},{},{},{},{},{},{},{},{},{:.1},{:.1},{},{},{}",
                        data.display(),
                        args[1],
                        c.marker.colour,
                        c.marker.area,
                        c.border.inside,
                        c.border.cloth,
                        c.border.outside,
                        c.peak_saturation,
                        c.border.runs_on,
                        dm[d] as u8,
                        tol,
                        c.marker.centre.x,
                        c.marker.centre.y,
                        counted_match[d] as u8,
                        c.peak_value,
                        c.border.cloth_value
                    )?;
                }
            }
            for (d, c) in dets.iter().enumerate() {
                if dm[d] {
                    continue;
                }
                let any_truth = expected
                    .iter()
                    .filter(|e| e.colour == c.marker.colour)
                    .map(|e| e.centre.distance(c.marker.centre))
                    .fold(f32::INFINITY, f32::min);
                let kind = if any_truth <= tol {
                    "duplicate / partly visible truth"
                } else if any_truth <= 2.0 * tol {
                    "off centre"
                } else if c.border.outside > 0 {
                    "far, touches mask edge"
                } else {
                    "far, inside"
                };
                if verbose {
                    println!(
                        "false f{index} {:?} {kind} (nearest truth {any_truth:.1}, tol {tol:.1})",
                        (c.marker, c.border, c.peak_saturation)
                    );
                }
                *false_kinds.entry(kind.to_string()).or_default() += 1;
            }
        }
        println!(
            "{}: recall {:.4} ({found} of {counted}), precision {:.4} ({correct} of {detections})",
            data.display(),
            found as f64 / counted.max(1) as f64,
            correct as f64 / detections.max(1) as f64
        );
        println!("  misses: {miss_reasons:?}");
        println!("  false: {false_kinds:?}");
    }
    Ok(())
}
