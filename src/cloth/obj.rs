//! Garments from Wavefront OBJ files.
//!
//! [`parse_obj`] reads the `v` (position) and `f` (face) lines of an OBJ file and ignores everything
//! else (`vt`, `vn`, `o`, `g`, `s`, `usemtl`, `mtllib`, `l`, comments). Face corners may be written
//! `v`, `v/vt`, `v//vn` or `v/vt/vn`; only the position index is used. Indices are 1-based, negative
//! indices count back from the last vertex defined so far. Polygons are triangulated as fans from
//! their first corner; triangles that repeat a vertex are dropped, and so are vertices no face uses.
//! Errors name the file and the line. Positions are taken as rest-pose world centimetres — the
//! garment must be modelled around the rig's rest pose (all channels zero: the shipped skeleton's
//! T-pose with the hip joint at the origin, Y up, facing +Z).
//!
//! [`load_garment`] adds anchors, since an OBJ carries none: every vertex within
//! [`DEFAULT_ANCHOR_BAND_CM`] of the mesh's highest point (the shoulders and neckline of a top, the
//! waistband of a skirt) is bound rigidly to one bone: the joint of the rest-pose trunk capsule
//! (pelvis, abdomen, chest, neck, …; not the arms) nearest to most of those vertices. One bone,
//! because anchors on two bones tear the cloth between them whenever the bones move apart. Hands to
//! the solver: a [`GarmentMesh`].

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::capsule::Capsule;
use super::garment::{rest_pose, to_bone_local, Anchor, GarmentMesh};
use super::proxies::{BodyRig, GROUP_TRUNK};

/// Vertices this close to the top of an OBJ garment become anchors, cm.
pub const DEFAULT_ANCHOR_BAND_CM: f32 = 3.0;

/// A triangle mesh read from an OBJ file.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjMesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// Why an OBJ file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ObjError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}, line {line}: {message}")]
    Parse {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{path}: no faces (a garment needs triangles or polygons on 'f' lines)")]
    NoFaces { path: PathBuf },
}

/// Reads an OBJ file.
pub fn load_obj(path: &Path) -> Result<ObjMesh, ObjError> {
    let bytes = std::fs::read(path).map_err(|source| ObjError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse_obj(&String::from_utf8_lossy(&bytes), path)
}

/// Parses OBJ text; `path` only names the source in errors.
pub fn parse_obj(text: &str, path: &Path) -> Result<ObjMesh, ObjError> {
    let error = |line: usize, message: String| ObjError::Parse {
        path: path.to_owned(),
        line,
        message,
    };
    let mut positions: Vec<Vec3> = Vec::new();
    // (triangle, line) so late positive indices can be checked against the final count.
    let mut triangles: Vec<([u32; 3], usize)> = Vec::new();
    let mut corners: Vec<u32> = Vec::new();
    for (number, raw) in text.lines().enumerate() {
        let line = number + 1;
        let content = raw.split('#').next().unwrap_or("");
        let mut tokens = content.split_whitespace();
        match tokens.next() {
            Some("v") => {
                let mut xyz = [0.0f32; 3];
                for (k, value) in xyz.iter_mut().enumerate() {
                    let token = tokens.next().ok_or_else(|| {
                        error(line, format!("vertex has {k} coordinates, expected 3"))
                    })?;
                    *value = token
                        .parse::<f32>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| error(line, format!("'{token}' is not a finite number")))?;
                }
                positions.push(Vec3::from(xyz));
            }
            Some("f") => {
                corners.clear();
                for token in tokens {
                    let index = token.split('/').next().unwrap_or("");
                    let value: i64 = index
                        .parse()
                        .map_err(|_| error(line, format!("'{token}' is not a vertex reference")))?;
                    let resolved = if value > 0 {
                        value - 1
                    } else if value < 0 {
                        positions.len() as i64 + value
                    } else {
                        return Err(error(
                            line,
                            "vertex index 0 (OBJ indices start at 1)".into(),
                        ));
                    };
                    if resolved < 0 || resolved > u32::MAX as i64 {
                        return Err(error(
                            line,
                            format!(
                                "vertex index {value} refers before the first vertex ({} defined so far)",
                                positions.len()
                            ),
                        ));
                    }
                    corners.push(resolved as u32);
                }
                if corners.len() < 3 {
                    return Err(error(
                        line,
                        format!(
                            "a face needs at least 3 vertices, this one has {}",
                            corners.len()
                        ),
                    ));
                }
                for k in 1..corners.len() - 1 {
                    let t = [corners[0], corners[k], corners[k + 1]];
                    if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                        triangles.push((t, line));
                    }
                }
            }
            _ => {}
        }
    }
    if let Some((t, line)) = triangles
        .iter()
        .find(|(t, _)| t.iter().any(|&v| v as usize >= positions.len()))
    {
        return Err(error(
            *line,
            format!(
                "face refers to vertex {} but the file defines {}",
                t.iter().map(|&v| v as usize + 1).max().unwrap_or(0),
                positions.len()
            ),
        ));
    }
    if triangles.is_empty() {
        return Err(ObjError::NoFaces {
            path: path.to_owned(),
        });
    }
    // Drop vertices no face uses, keeping the order of the rest.
    let mut used = vec![false; positions.len()];
    for (t, _) in &triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut remap = vec![u32::MAX; positions.len()];
    let mut kept = Vec::with_capacity(positions.len());
    for (v, p) in positions.iter().enumerate() {
        if used[v] {
            remap[v] = kept.len() as u32;
            kept.push(*p);
        }
    }
    Ok(ObjMesh {
        positions: kept,
        triangles: triangles
            .into_iter()
            .map(|(t, _)| t.map(|v| remap[v as usize]))
            .collect(),
    })
}

/// An OBJ garment for `rig`, anchored with the default band.
pub fn load_garment(path: &Path, rig: &BodyRig) -> Result<GarmentMesh, ObjError> {
    load_garment_with_band(path, rig, DEFAULT_ANCHOR_BAND_CM)
}

/// An OBJ garment for `rig`: vertices within `band_cm` of the top are anchored to the joint of the
/// nearest rest-pose capsule.
pub fn load_garment_with_band(
    path: &Path,
    rig: &BodyRig,
    band_cm: f32,
) -> Result<GarmentMesh, ObjError> {
    let mesh = load_obj(path)?;
    Ok(garment_from_mesh(obj_name(path), mesh, rig, band_cm))
}

/// An OBJ garment's name: its file's stem.
pub fn obj_name(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "obj".into())
}

/// Anchors a mesh on `rig` (see [`load_garment_with_band`]).
pub fn garment_from_mesh(name: String, mesh: ObjMesh, rig: &BodyRig, band_cm: f32) -> GarmentMesh {
    let pose = rest_pose(rig);
    let top = mesh
        .positions
        .iter()
        .map(|p| p.y)
        .fold(f32::NEG_INFINITY, f32::max);
    let prepared: Vec<_> = pose.capsules.iter().map(Capsule::prepared).collect();
    let band: Vec<usize> = (0..mesh.positions.len())
        .filter(|&v| mesh.positions[v].y >= top - band_cm.max(0.0))
        .collect();
    // One bone for the whole band: the joint of the trunk capsule nearest to most band vertices
    // (anchors on two bones would tear the cloth between them whenever the bones move apart).
    let mut votes: Vec<(usize, usize)> = Vec::new();
    for &v in &band {
        let p = mesh.positions[v];
        let nearest = prepared
            .iter()
            .zip(rig.proxies())
            .filter(|(_, proxy)| proxy.group == GROUP_TRUNK)
            .map(|(c, proxy)| (c.distance(p.into()), proxy.joint))
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        if let Some((_, joint)) = nearest {
            match votes.iter_mut().find(|(j, _)| *j == joint) {
                Some(entry) => entry.1 += 1,
                None => votes.push((joint, 1)),
            }
        }
    }
    let bone = votes
        .iter()
        .max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(&a.0)))
        .map_or(0, |(j, _)| *j);
    let anchors = band
        .into_iter()
        .map(|v| Anchor {
            vertex: v as u32,
            bone,
            local: to_bone_local(&pose.bones, bone, mesh.positions[v]),
            slack_cm: 0.0,
        })
        .collect();
    GarmentMesh {
        name,
        positions: mesh.positions,
        triangles: mesh.triangles,
        anchors,
        cuffs: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn parse(text: &str) -> Result<ObjMesh, ObjError> {
        parse_obj(text, Path::new("test.obj"))
    }

    #[test]
    fn reads_polygons_and_index_forms() {
        let text =
            "# a quad and a triangle\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n\
                    f 1/1/1 2/1/1 3//1 4\nv 2 0 0\nf -4 -1 -3\nv 9 9 9\n";
        let mesh = parse(text).expect("parse");
        assert_eq!(mesh.positions.len(), 5, "unused vertex dropped");
        // Quad 1 2 3 4 → fan (1 2 3) (1 3 4); -4 −1 −3 with 5 vertices → 2 5 3.
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
    }

    #[test]
    fn errors_name_file_and_line() {
        let e = parse("v 0 0 0\nv 1 0 0\nf 1 2 3\n").expect_err("index past end");
        assert_eq!(
            e.to_string(),
            "test.obj, line 3: face refers to vertex 3 but the file defines 2"
        );
        let e = parse("v 0 0\n").expect_err("short vertex");
        assert!(e.to_string().contains("line 1"), "{e}");
        let e = parse("v 0 0 nan\n").expect_err("nan");
        assert!(e.to_string().contains("finite"), "{e}");
        let e = parse("v 0 0 0\nv 0 0 0\nv 0 0 0\nf 0 1 2\n").expect_err("zero");
        assert!(e.to_string().contains("line 4"), "{e}");
        let e = parse("v 0 0 0\nf -2 1 1\n").expect_err("negative");
        assert!(e.to_string().contains("before the first vertex"), "{e}");
        assert!(matches!(parse("v 0 0 0\n"), Err(ObjError::NoFaces { .. })));
        let e = load_obj(Path::new("/nonexistent/shirt.obj")).expect_err("missing");
        assert!(e
            .to_string()
            .starts_with("/nonexistent/shirt.obj: cannot read"));
    }

    #[test]
    fn obj_garment_is_anchored_at_its_top() {
        let rig = crate::cloth::garment::tests::chidi();
        let skirt = crate::cloth::garment::GarmentMesh::generate(
            crate::cloth::garment::GarmentKind::Skirt,
            &rig,
            &crate::cloth::garment::GarmentParams::live(),
        )
        .expect("skirt");
        let mut text = String::new();
        for p in &skirt.positions {
            text += &format!("v {} {} {}\n", p.x, p.y, p.z);
        }
        for t in &skirt.triangles {
            text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        let dir = tempfile::tempdir().expect("tempdir");
        let file = dir.path().join("skirt.obj");
        std::fs::write(&file, text).expect("write");
        let garment = load_garment(&file, &rig).expect("load");
        assert_eq!(garment.name, "skirt");
        assert_eq!(garment.triangles, skirt.triangles);
        // The waist ring (and the ring below it, 2 cm down) lie within the 3 cm band, on the hip
        // or abdomen.
        let top = garment
            .positions
            .iter()
            .map(|p| p.y)
            .fold(f32::MIN, f32::max);
        assert!(!garment.anchors.is_empty());
        for a in &garment.anchors {
            assert!(garment.positions[a.vertex as usize].y >= top - 3.0);
            let name = &rig.skeleton().joint(a.bone).name;
            assert!(name == "hip" || name == "abdomen", "{name}");
        }
        garment.validate().expect("valid");
    }

    proptest! {
        #[test]
        fn arbitrary_text_never_panics(text in "\\PC{0,400}") {
            let _ = parse(&text);
        }

        #[test]
        fn obj_like_text_never_panics(lines in prop::collection::vec(
            prop_oneof![
                (any::<f32>(), any::<f32>(), any::<f32>()).prop_map(|(x, y, z)| format!("v {x} {y} {z}")),
                prop::collection::vec(-8i64..8, 0..6).prop_map(|ix| {
                    let mut s = String::from("f");
                    for i in ix { s += &format!(" {i}/1/{i}"); }
                    s
                }),
                "[vf#/ 0-9.-]{0,20}",
            ],
            0..30,
        )) {
            let text = lines.join("\n");
            if let Ok(mesh) = parse(&text) {
                for t in &mesh.triangles {
                    for &v in t {
                        prop_assert!((v as usize) < mesh.positions.len());
                    }
                }
            }
        }
    }
}
