//! Reading and writing grid graphs in the GCG1 binary format, and min-cut labellings in `.labels`.
//!
//! GCG1 (little-endian, no padding): magic `GCG1`; u32 H (rows); u32 W (columns); `f32[H*W]` src;
//! `f32[H*W]` sink; `f32[H*(W-1)]` right; `f32[(H-1)*W]` down; the file is exactly
//! 12 + 4*(2HW + H(W-1) + (H-1)W) bytes. `.labels`: H*W bytes, row-major, 1 = source side.
//!
//! This is how the segmenter's graphs are dumped for offline checks and how reference graphs and
//! reference cuts (from the outside oracle) are loaded: it gives a validated
//! [`super::maxflow::GridGraph`] to the max-flow solver, or a `Vec<bool>` labelling
//! (`true` = source side) to compare its result with. Every error names the file and what is wrong.

use std::path::{Path, PathBuf};

use super::maxflow::{GraphError, GridGraph};

const MAGIC: &[u8; 4] = b"GCG1";
const HEADER: usize = 12;
/// Name used in errors for data that did not come from a file.
const IN_MEMORY: &str = "<memory>";

/// What went wrong reading or writing a GCG1 or `.labels` file.
#[derive(Debug, thiserror::Error)]
pub enum GcgError {
    #[error("{path}: {source}", path = .path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: bad magic {found:?}, expected \"GCG1\"", path = .path.display())]
    BadMagic { path: PathBuf, found: Vec<u8> },
    #[error("{path}: file is {actual} bytes, expected {expected} for H={height} W={width}", path = .path.display())]
    SizeMismatch {
        path: PathBuf,
        height: u64,
        width: u64,
        expected: u64,
        actual: u64,
    },
    #[error("{path}: grid H={height} W={width} is too large", path = .path.display())]
    TooLarge {
        path: PathBuf,
        height: u64,
        width: u64,
    },
    #[error("{path}: non-finite or negative capacity {value} in `{field}` at index {index}", path = .path.display())]
    BadCapacity {
        path: PathBuf,
        field: &'static str,
        index: usize,
        value: f32,
    },
    #[error("{path}: {source}", path = .path.display())]
    Graph {
        path: PathBuf,
        #[source]
        source: GraphError,
    },
    #[error("{path}: label byte {value} at node {index} is neither 0 nor 1", path = .path.display())]
    BadLabel {
        path: PathBuf,
        index: usize,
        value: u8,
    },
}

/// Expected GCG1 file size for H rows and W columns, if it fits in u64.
fn gcg_size(h: u64, w: u64) -> Option<u64> {
    let n = h.checked_mul(w)?;
    let right = h.checked_mul(w.saturating_sub(1))?;
    let down = h.saturating_sub(1).checked_mul(w)?;
    let floats = n.checked_mul(2)?.checked_add(right)?.checked_add(down)?;
    floats.checked_mul(4)?.checked_add(HEADER as u64)
}

fn parse_at(bytes: &[u8], path: &Path) -> Result<GridGraph, GcgError> {
    let p = || path.to_path_buf();
    if bytes.len() < 4 || &bytes[..4] != MAGIC {
        return Err(GcgError::BadMagic {
            path: p(),
            found: bytes[..bytes.len().min(4)].to_vec(),
        });
    }
    if bytes.len() < HEADER {
        return Err(GcgError::SizeMismatch {
            path: p(),
            height: 0,
            width: 0,
            expected: HEADER as u64,
            actual: bytes.len() as u64,
        });
    }
    let u32_at =
        |o: usize| u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let (h, w) = (u32_at(4) as u64, u32_at(8) as u64);
    let expected = gcg_size(h, w).ok_or(GcgError::TooLarge {
        path: p(),
        height: h,
        width: w,
    })?;
    if bytes.len() as u64 != expected {
        return Err(GcgError::SizeMismatch {
            path: p(),
            height: h,
            width: w,
            expected,
            actual: bytes.len() as u64,
        });
    }
    // The file really holds all these floats, so the counts fit in usize.
    let (hu, wu) = (h as usize, w as usize);
    let counts: [(&'static str, usize); 4] = [
        ("src", hu * wu),
        ("sink", hu * wu),
        ("right", hu * wu.saturating_sub(1)),
        ("down", hu.saturating_sub(1) * wu),
    ];
    let mut off = HEADER;
    let mut arrays: Vec<Vec<f32>> = Vec::with_capacity(4);
    for (field, count) in counts {
        let chunk = &bytes[off..off + 4 * count];
        off += 4 * count;
        let mut v = Vec::with_capacity(count);
        for (index, c) in chunk.chunks_exact(4).enumerate() {
            let value = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            if !(value.is_finite() && value >= 0.0) {
                return Err(GcgError::BadCapacity {
                    path: p(),
                    field,
                    index,
                    value,
                });
            }
            v.push(value);
        }
        arrays.push(v);
    }
    let down = arrays.pop().unwrap_or_default();
    let right = arrays.pop().unwrap_or_default();
    let sink = arrays.pop().unwrap_or_default();
    let src = arrays.pop().unwrap_or_default();
    GridGraph::from_parts(wu, hu, src, sink, right, down).map_err(|source| match source {
        GraphError::TooLarge { .. } => GcgError::TooLarge {
            path: p(),
            height: h,
            width: w,
        },
        source => GcgError::Graph { path: p(), source },
    })
}

/// Parses GCG1 bytes (errors name the source as `<memory>`).
pub fn parse_gcg(bytes: &[u8]) -> Result<GridGraph, GcgError> {
    parse_at(bytes, Path::new(IN_MEMORY))
}

/// Reads and validates a GCG1 file.
pub fn read_gcg(path: &Path) -> Result<GridGraph, GcgError> {
    let bytes = std::fs::read(path).map_err(|source| GcgError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_at(&bytes, path)
}

/// Encodes a graph as GCG1 bytes.
///
/// Graph dimensions always fit in u32 (a [`GridGraph`] is limited to 32-bit node numbers).
pub fn encode_gcg(g: &GridGraph) -> Vec<u8> {
    let floats = g.source().len() + g.sink().len() + g.right().len() + g.down().len();
    let mut out = Vec::with_capacity(HEADER + 4 * floats);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(g.height() as u32).to_le_bytes());
    out.extend_from_slice(&(g.width() as u32).to_le_bytes());
    for a in [g.source(), g.sink(), g.right(), g.down()] {
        for v in a {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// Writes a graph as a GCG1 file.
pub fn write_gcg(path: &Path, g: &GridGraph) -> Result<(), GcgError> {
    std::fs::write(path, encode_gcg(g)).map_err(|source| GcgError::Io {
        path: path.to_path_buf(),
        source,
    })
}

fn parse_labels_at(
    bytes: &[u8],
    width: usize,
    height: usize,
    path: &Path,
) -> Result<Vec<bool>, GcgError> {
    let n = width.checked_mul(height).ok_or(GcgError::TooLarge {
        path: path.to_path_buf(),
        height: height as u64,
        width: width as u64,
    })?;
    if bytes.len() != n {
        return Err(GcgError::SizeMismatch {
            path: path.to_path_buf(),
            height: height as u64,
            width: width as u64,
            expected: n as u64,
            actual: bytes.len() as u64,
        });
    }
    bytes
        .iter()
        .enumerate()
        .map(|(index, &value)| match value {
            0 => Ok(false),
            1 => Ok(true),
            value => Err(GcgError::BadLabel {
                path: path.to_path_buf(),
                index,
                value,
            }),
        })
        .collect()
}

/// Parses `.labels` bytes: `width*height` bytes, row-major, 1 = source side, 0 = sink side.
pub fn parse_labels(bytes: &[u8], width: usize, height: usize) -> Result<Vec<bool>, GcgError> {
    parse_labels_at(bytes, width, height, Path::new(IN_MEMORY))
}

/// Reads a `.labels` file for a `width` x `height` grid.
pub fn read_labels(path: &Path, width: usize, height: usize) -> Result<Vec<bool>, GcgError> {
    let bytes = std::fs::read(path).map_err(|source| GcgError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_labels_at(&bytes, width, height, path)
}

/// Encodes a labelling as `.labels` bytes.
pub fn encode_labels(labels: &[bool]) -> Vec<u8> {
    labels.iter().map(|&l| l as u8).collect()
}

/// Writes a labelling as a `.labels` file.
pub fn write_labels(path: &Path, labels: &[bool]) -> Result<(), GcgError> {
    std::fs::write(path, encode_labels(labels)).map_err(|source| GcgError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::segment::maxflow::GridMaxFlow;

    fn data(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/maxflow")
            .join(name)
    }

    fn sample() -> GridGraph {
        let (w, h) = (5, 3);
        let f = |k: usize, s: f32| (0..k).map(|i| (i as f32) * s).collect::<Vec<_>>();
        GridGraph::from_parts(w, h, f(15, 0.5), f(15, 0.25), f(12, 1.5), f(10, 2.0)).unwrap()
    }

    #[test]
    fn round_trip() {
        let g = sample();
        let bytes = encode_gcg(&g);
        assert_eq!(bytes.len() as u64, gcg_size(3, 5).unwrap());
        assert_eq!(bytes.len(), 12 + 4 * (2 * 15 + 3 * 4 + 2 * 5));
        assert_eq!(parse_gcg(&bytes).unwrap(), g);
        let dir = std::env::temp_dir().join(format!("gcg_rt_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("g.gcg");
        write_gcg(&p, &g).unwrap();
        assert_eq!(read_gcg(&p).unwrap(), g);
        let labels = vec![
            true, false, true, true, false, false, true, false, true, true, false, false, true,
            false, true,
        ];
        let lp = dir.join("g.labels");
        write_labels(&lp, &labels).unwrap();
        assert_eq!(read_labels(&lp, 5, 3).unwrap(), labels);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn truncated_and_bad_magic_are_errors() {
        let bytes = encode_gcg(&sample());
        for cut in [0, 3, 4, 11, 12, 100, bytes.len() - 1] {
            let e = parse_gcg(&bytes[..cut]).unwrap_err();
            assert!(
                matches!(e, GcgError::SizeMismatch { .. } | GcgError::BadMagic { .. }),
                "{cut}: {e}"
            );
        }
        let e = parse_gcg(&bytes[..100]).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("<memory>")
                && msg.contains("100")
                && msg.contains(&bytes.len().to_string()),
            "{msg}"
        );
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(matches!(
            parse_gcg(&longer),
            Err(GcgError::SizeMismatch { .. })
        ));
        let mut bad = bytes.clone();
        bad[0] = b'X';
        assert!(matches!(parse_gcg(&bad), Err(GcgError::BadMagic { .. })));
        // Huge dimensions in the header must not allocate or overflow.
        let mut huge = bytes.clone();
        huge[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        huge[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(parse_gcg(&huge).is_err());
        // Missing file: error names it.
        let e = read_gcg(Path::new("/nonexistent/x.gcg")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/x.gcg"));
    }

    #[test]
    fn bad_capacities_are_errors() {
        let mut bytes = encode_gcg(&sample());
        // sink[2] := -1
        let o = 12 + 4 * (15 + 2);
        bytes[o..o + 4].copy_from_slice(&(-1.0f32).to_le_bytes());
        let e = parse_gcg(&bytes).unwrap_err();
        assert!(
            matches!(
                e,
                GcgError::BadCapacity {
                    field: "sink",
                    index: 2,
                    ..
                }
            ),
            "{e}"
        );
        let o = 12 + 4 * (30 + 12 + 7); // down[7] := NaN
        let mut bytes = encode_gcg(&sample());
        bytes[o..o + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        let e = parse_gcg(&bytes).unwrap_err();
        assert!(
            matches!(
                e,
                GcgError::BadCapacity {
                    field: "down",
                    index: 7,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("down"));
    }

    #[test]
    fn labels_errors() {
        assert!(matches!(
            parse_labels(&[0, 1, 2, 0], 2, 2),
            Err(GcgError::BadLabel {
                index: 2,
                value: 2,
                ..
            })
        ));
        assert!(matches!(
            parse_labels(&[0, 1, 1], 2, 2),
            Err(GcgError::SizeMismatch { .. })
        ));
        assert_eq!(
            parse_labels(&[0, 1, 1, 0], 2, 2).unwrap(),
            vec![false, true, true, false]
        );
    }

    #[test]
    fn reference_64x48() {
        let g = read_gcg(&data("seg_64x48_s3.gcg")).unwrap();
        assert_eq!((g.width(), g.height()), (64, 48));
        let reference = read_labels(&data("seg_64x48_s3.labels"), 64, 48).unwrap();
        let r = GridMaxFlow::new().solve(&g);
        let want = 1987.333256f64;
        assert!(
            (r.flow - want).abs() <= 1e-5 * want,
            "flow {} want {want}",
            r.flow
        );
        let cut = g.cut_cost(&r.labels);
        assert!((cut - want).abs() <= 1e-5 * want, "cut {cut} want {want}");
        assert!((g.cut_cost(&reference) - want).abs() <= 1e-5 * want);
        let fg = r.labels.iter().filter(|&&l| l).count();
        assert_eq!(fg, 194);
        assert_eq!(r.labels, reference);
    }
}
