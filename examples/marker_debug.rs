//! Debug aid for the marker detector: prints the per-pixel labels around a point of one frame.
//!
//! `cargo run --release --example marker_debug -- DATASET FRAME X Y [MASKS] [RADIUS]`
//! Letters: R/C/P marker colours (upper case inside the mask, lower case outside), `.` cloth,
//! `-` other inside the mask, ` ` outside. Truth markers within the window are listed.
use std::path::Path;

use suitcap::segment::features::{classify, MarkerGate};
use suitcap::suit::SuitDefinition;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    anyhow::ensure!(args.len() >= 5, "usage: DATASET FRAME X Y [MASKS] [RADIUS]");
    let data = Path::new(&args[1]);
    let frame: usize = args[2].parse()?;
    let (cx, cy): (f32, f32) = (args[3].parse()?, args[4].parse()?);
    let masks = args
        .get(5)
        .map(|s| Path::new(s).to_path_buf())
        .unwrap_or(data.join("masks"));
    let r: i32 = args.get(6).map(|s| s.parse()).transpose()?.unwrap_or(8);
    let suit = SuitDefinition::load_dir(Path::new("suits/default"))?;
    let gate = MarkerGate::new(&suit);
    let name = format!("{frame:06}.png");
    let img = image::open(data.join("frames").join(&name))?.to_rgb8();
    let mask = image::open(masks.join(&name))?.to_luma8();
    let letters = ['R', 'C', 'P'];
    let hue_of = |h: u8| {
        let hue = (h as f32 + 0.5) * 360.0 / 256.0;
        suit.markers
            .iter()
            .enumerate()
            .map(|(i, m)| (i, suitcap::colour::hue_distance(hue, m.hsv.hue)))
            .filter(|&(_, d)| d <= suit.detection.hue_tolerance_deg)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    };
    let (x0, y0) = (cx as i32 - r, cy as i32 - r);
    print!("     ");
    for x in x0..=x0 + 2 * r {
        print!("{}", (x.rem_euclid(10)));
    }
    println!();
    for y in y0..=y0 + 2 * r {
        print!("{y:4} ");
        for x in x0..=x0 + 2 * r {
            if x < 0 || y < 0 || x >= img.width() as i32 || y >= img.height() as i32 {
                print!("~");
                continue;
            }
            let p = img.get_pixel(x as u32, y as u32).0;
            let c = classify(p[0], p[1], p[2]);
            let inside = mask.get_pixel(x as u32, y as u32).0[0] > 127;
            let ch = if gate.is_marker(c) {
                hue_of(c.hue).map(|i| letters[i]).unwrap_or('?')
            } else if gate.is_cloth(c) {
                '.'
            } else {
                '-'
            };
            let ch = if inside {
                ch
            } else if ch.is_ascii_uppercase() {
                ch.to_ascii_lowercase()
            } else if ch == '.' {
                ','
            } else {
                ' '
            };
            print!("{ch}");
        }
        println!();
    }
    // HSV along the centre row.
    for x in x0..=x0 + 2 * r {
        if x >= 0 && (x as u32) < img.width() && cy >= 0.0 {
            let p = img.get_pixel(x as u32, cy as u32).0;
            let c = classify(p[0], p[1], p[2]);
            print!(
                "{}:{:?}h{}s{}v{} ",
                x,
                p,
                (c.hue as f32 * 360.0 / 256.0) as u32,
                c.sat,
                c.val
            );
        }
    }
    println!();
    let text = std::fs::read_to_string(data.join("markers.csv"))?;
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() < 7 || f[0].parse::<usize>().ok() != Some(frame) {
            continue;
        }
        let (x, y): (f32, f32) = (f[3].parse()?, f[4].parse()?);
        if (x - cx).abs() <= r as f32 && (y - cy).abs() <= r as f32 {
            println!("truth {line}");
        }
    }
    Ok(())
}
