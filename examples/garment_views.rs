//! Debug aid: the garment and the body's capsules seen from four sides, after simulating a motion.
//!
//! `cargo run --release --example garment_views -- MOTION.bvh FRAME OUT.png [tshirt|skirt|dress] [live]`
//! Simulates the motion's frames 0..=FRAME (quality mode unless `live`, sized for the motion's own
//! skeleton) and draws the capsules in grey and the garment over them from the world's +Z, +X, −Z
//! and −X (the rest pose faces +Z), side by side, looking at the chest (25 cm above the capsules'
//! mean). Frames whose maximum edge strain passes 10 % or whose deepest vertex is more than 2 mm
//! inside a capsule are listed. `VIEW_SIZE` (pixels per view, default 360) and `VIEW_FOV`
//! (horizontal degrees, default 30; e.g. 16 for a closer look) change the views.
use std::path::Path;

use glam::Vec3;
use image::RgbImage;
use suitcap::body_size::Silhouette;
use suitcap::bvh::Motion;
use suitcap::camera::{Camera, Intrinsics};
use suitcap::cloth::Capsule;
use suitcap::composite::Compositor;
use suitcap::mask::Mask;
use suitcap::render::capsule_mesh::CapsuleMesh;
use suitcap::render::{GarmentRenderer, GarmentStyle, RenderSettings};
use suitcap::tryon::{ClothOptions, ClothStage, GarmentChoice, SimulationMode};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    anyhow::ensure!(args.len() >= 4, "usage: MOTION FRAME OUT [garment] [live]");
    let motion = Motion::load(Path::new(&args[1]))?;
    let last: usize = args[2].parse()?;
    anyhow::ensure!(motion.frame_count() > 0, "{} has no frames", args[1]);
    let garment = args.get(4).map(String::as_str).unwrap_or("tshirt");
    let mode = if args.get(5).is_some() {
        SimulationMode::Live
    } else {
        SimulationMode::Quality
    };
    let mut options = ClothOptions::new(GarmentChoice::parse(garment)?, mode);
    options.known_size = Some(suitcap::body_size::BodySize::TEMPLATE);
    let mut stage = ClothStage::new(&motion.skeleton, options)?;
    let size: u32 = std::env::var("VIEW_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(360);
    let intr = Intrinsics::from_fov(
        size,
        size,
        std::env::var("VIEW_FOV")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(30.0),
    );
    // The stage wants a camera for the silhouette-based sizing, which a known size skips.
    let dummy = Camera::look_at(intr, Vec3::new(0.0, 100.0, 400.0), Vec3::ZERO, Vec3::Y);
    let empty = Mask::empty(size, size);
    let fps = motion.frame_rate();
    let mut cloth = None;
    for k in 0..=last.min(motion.frame_count() - 1) {
        let silhouette = Silhouette::whole(&empty);
        let c = stage.advance(motion.frame(k), k as f64 / fps, true, silhouette, &dummy)?;
        if let Some(q) = &c.quality {
            if q.strain_max > 0.10 || q.penetration_cm > 0.2 {
                println!(
                    "frame {k}: strain max {:.1} %, pen {:.1} mm",
                    100.0 * q.strain_max,
                    10.0 * q.penetration_cm
                );
            }
        }
        cloth = Some(c);
    }
    let cloth = cloth.ok_or_else(|| anyhow::anyhow!("no frames"))?;
    anyhow::ensure!(!cloth.positions.is_empty(), "garment not worn");
    // Body centre: mean of the capsule ends.
    let centre = cloth
        .capsules
        .iter()
        .map(|c| 0.5 * (c.a + c.b))
        .sum::<Vec3>()
        / cloth.capsules.len() as f32;
    let target = centre + Vec3::Y * 25.0;
    // The capsules as one grey mesh.
    let mesh = CapsuleMesh::new(24, 6);
    let (mut bv, mut bt) = (Vec::new(), Vec::new());
    let mut buf = Vec::new();
    for c in &cloth.capsules {
        buf.clear();
        // Shrunk as the renderer's depth pass shrinks them, so cloth lying on the body shows.
        if let Some(cone) = mesh.vertices(c, RenderSettings::default().capsule_inset, &mut buf) {
            let base = bv.len() as u32;
            bv.extend_from_slice(&buf);
            bt.extend(mesh.triangles(cone).iter().map(|t| t.map(|i| i + base)));
        }
    }
    let grey = RenderSettings {
        style: GarmentStyle {
            front: [170, 170, 170],
            back: [90, 90, 90],
        },
        ..RenderSettings::default()
    };
    let mut body_renderer = GarmentRenderer::new(grey);
    let mut renderer = GarmentRenderer::default();
    let mut compositor = Compositor::new(false);
    let mut sheet = RgbImage::from_pixel(size * 4, size, image::Rgb([255, 255, 255]));
    for (v, dir) in [Vec3::Z, Vec3::X, -Vec3::Z, -Vec3::X].iter().enumerate() {
        let eye = target + *dir * 330.0;
        let camera = Camera::look_at(intr, eye, target, Vec3::Y);
        let mut view = RgbImage::from_pixel(size, size, image::Rgb([255, 255, 255]));
        let none: [Capsule; 0] = [];
        let layer = body_renderer.render(&camera, &bv, &bt, &none);
        compositor.composite(&mut view, layer)?;
        let layer = renderer.render(
            &camera,
            &cloth.positions,
            &cloth.triangles,
            &cloth.occluders,
        );
        compositor.composite(&mut view, layer)?;
        image::imageops::replace(&mut sheet, &view, (v as u32 * size) as i64, 0);
    }
    sheet.save(&args[3])?;
    if let Some(q) = cloth.quality {
        println!("{q:?}");
    }
    Ok(())
}
