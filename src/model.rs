//! Model files: named arrays of `f32` in one checked binary file.
//!
//! Every trained part of a suit (segmenter tables, codebooks, regressor) is stored as a [`ModelFile`]:
//!
//! ```text
//! magic "SUITCAP\0" · u32 format version · kind (u32 length + UTF-8) · u32 kind version ·
//! u32 array count · per array: name (u32 length + UTF-8), u32 rank, u32 dims…, f32 data… ·
//! u64 FNV-1a checksum of everything before it
//! ```
//!
//! all little-endian. Reading checks the magic, both versions, the kind, every length and the checksum,
//! so a missing, truncated, corrupt or foreign file is a clear error that names the file (and the
//! array), never a panic or a silently wrong model. Files are written atomically.

use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"SUITCAP\0";
/// Version of the container layout.
pub const CONTAINER_VERSION: u32 = 1;

/// A named, shaped array of `f32`.
#[derive(Clone, Debug, PartialEq)]
pub struct Array {
    pub name: String,
    pub dims: Vec<usize>,
    pub data: Vec<f32>,
}

/// The arrays of one model file, with its kind (e.g. "segmenter") and the kind's version.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelFile {
    pub kind: String,
    pub version: u32,
    pub arrays: Vec<Array>,
}

/// A model file that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    #[error("{path}: missing (train it first, e.g. with suitcap-train)")]
    Missing { path: PathBuf },
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: cannot write: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not a suitcap model file (bad magic)")]
    Magic { path: PathBuf },
    #[error("{path}: truncated or corrupt ({what})")]
    Corrupt { path: PathBuf, what: String },
    #[error("{path}: is a '{found}' model, expected '{expected}'")]
    Kind {
        path: PathBuf,
        found: String,
        expected: String,
    },
    #[error(
        "{path}: '{kind}' model version {found}, this build reads version {expected}; retrain it"
    )]
    Version {
        path: PathBuf,
        kind: String,
        found: u32,
        expected: u32,
    },
    #[error("{path}: array '{name}' {message}")]
    Array {
        path: PathBuf,
        name: String,
        message: String,
    },
}

pub(crate) fn fnv1a(bytes: &[u8]) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for &b in bytes {
        hash ^= u64::from(b);
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    hash
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    path: &'a Path,
}

impl Reader<'_> {
    fn take(&mut self, n: usize, what: &str) -> Result<&[u8], ModelError> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| ModelError::Corrupt {
                path: self.path.to_owned(),
                what: format!("ends inside {what}"),
            })?;
        let slice = &self.bytes[self.at..end];
        self.at = end;
        Ok(slice)
    }

    fn u32(&mut self, what: &str) -> Result<u32, ModelError> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn string(&mut self, what: &str) -> Result<String, ModelError> {
        let n = self.u32(what)? as usize;
        let b = self.take(n, what)?;
        String::from_utf8(b.to_vec()).map_err(|_| ModelError::Corrupt {
            path: self.path.to_owned(),
            what: format!("{what} is not UTF-8"),
        })
    }
}

impl ModelFile {
    pub fn new(kind: &str, version: u32) -> ModelFile {
        ModelFile {
            kind: kind.to_owned(),
            version,
            arrays: Vec::new(),
        }
    }

    /// Adds an array; `data.len()` must equal the product of `dims`.
    pub fn push(&mut self, name: &str, dims: &[usize], data: Vec<f32>) {
        debug_assert_eq!(dims.iter().product::<usize>(), data.len(), "array {name}");
        self.arrays.push(Array {
            name: name.to_owned(),
            dims: dims.to_vec(),
            data,
        });
    }

    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&CONTAINER_VERSION.to_le_bytes());
        let put_str = |out: &mut Vec<u8>, s: &str| {
            out.extend_from_slice(&(s.len() as u32).to_le_bytes());
            out.extend_from_slice(s.as_bytes());
        };
        put_str(&mut out, &self.kind);
        out.extend_from_slice(&self.version.to_le_bytes());
        out.extend_from_slice(&(self.arrays.len() as u32).to_le_bytes());
        for a in &self.arrays {
            put_str(&mut out, &a.name);
            out.extend_from_slice(&(a.dims.len() as u32).to_le_bytes());
            for &d in &a.dims {
                out.extend_from_slice(&(d as u32).to_le_bytes());
            }
            for &v in &a.data {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        let checksum = fnv1a(&out);
        out.extend_from_slice(&checksum.to_le_bytes());
        out
    }

    /// Writes the file atomically.
    pub fn write(&self, path: &Path) -> Result<(), ModelError> {
        crate::io::write_atomic(path, &self.encode()).map_err(|source| ModelError::Write {
            path: path.to_owned(),
            source,
        })
    }

    /// Reads a file of `kind` at `version`.
    pub fn read(path: &Path, kind: &str, version: u32) -> Result<ModelFile, ModelError> {
        let bytes = std::fs::read(path).map_err(|source| {
            if source.kind() == std::io::ErrorKind::NotFound {
                ModelError::Missing {
                    path: path.to_owned(),
                }
            } else {
                ModelError::Io {
                    path: path.to_owned(),
                    source,
                }
            }
        })?;
        ModelFile::decode(&bytes, path, kind, version)
    }

    /// Decodes bytes; `path` names the source in errors.
    pub fn decode(
        bytes: &[u8],
        path: &Path,
        kind: &str,
        version: u32,
    ) -> Result<ModelFile, ModelError> {
        if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
            return Err(ModelError::Magic {
                path: path.to_owned(),
            });
        }
        if bytes.len() < MAGIC.len() + 12 {
            return Err(ModelError::Corrupt {
                path: path.to_owned(),
                what: "ends inside the header".into(),
            });
        }
        let (body, tail) = bytes.split_at(bytes.len() - 8);
        let mut stored = [0u8; 8];
        stored.copy_from_slice(tail);
        let checksum_ok = u64::from_le_bytes(stored) == fnv1a(body);
        let mut r = Reader {
            bytes: body,
            at: MAGIC.len(),
            path,
        };
        let container = r.u32("the header")?;
        if container != CONTAINER_VERSION {
            return Err(ModelError::Version {
                path: path.to_owned(),
                kind: "container".into(),
                found: container,
                expected: CONTAINER_VERSION,
            });
        }
        let found_kind = r.string("the kind")?;
        if found_kind != kind {
            return Err(ModelError::Kind {
                path: path.to_owned(),
                found: found_kind,
                expected: kind.to_owned(),
            });
        }
        let found_version = r.u32("the version")?;
        if found_version != version {
            return Err(ModelError::Version {
                path: path.to_owned(),
                kind: kind.to_owned(),
                found: found_version,
                expected: version,
            });
        }
        if !checksum_ok {
            return Err(ModelError::Corrupt {
                path: path.to_owned(),
                what: "checksum mismatch".into(),
            });
        }
        let count = r.u32("the array count")?;
        let mut arrays = Vec::new();
        for _ in 0..count {
            let name = r.string("an array name")?;
            let rank = r.u32(&format!("array '{name}'"))? as usize;
            if rank > 8 {
                return Err(ModelError::Array {
                    path: path.to_owned(),
                    name,
                    message: format!("has rank {rank}"),
                });
            }
            let mut dims = Vec::with_capacity(rank);
            for _ in 0..rank {
                dims.push(r.u32(&format!("array '{name}'"))? as usize);
            }
            let len = dims
                .iter()
                .try_fold(1usize, |a, &d| a.checked_mul(d))
                .unwrap_or(usize::MAX);
            let raw = r.take(len.saturating_mul(4), &format!("array '{name}'"))?;
            let data: Vec<f32> = raw
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            if let Some(i) = data.iter().position(|v| !v.is_finite()) {
                return Err(ModelError::Array {
                    path: path.to_owned(),
                    name,
                    message: format!("value {i} is not finite"),
                });
            }
            arrays.push(Array { name, dims, data });
        }
        if r.at != body.len() {
            return Err(ModelError::Corrupt {
                path: path.to_owned(),
                what: "trailing bytes".into(),
            });
        }
        Ok(ModelFile {
            kind: found_kind,
            version: found_version,
            arrays,
        })
    }

    /// The array `name` with exactly `dims`, or an error naming the file and the array.
    pub fn array(&self, path: &Path, name: &str, dims: &[usize]) -> Result<&[f32], ModelError> {
        let a = self
            .arrays
            .iter()
            .find(|a| a.name == name)
            .ok_or_else(|| ModelError::Array {
                path: path.to_owned(),
                name: name.to_owned(),
                message: "is missing".into(),
            })?;
        if a.dims != dims {
            return Err(ModelError::Array {
                path: path.to_owned(),
                name: name.to_owned(),
                message: format!("has shape {:?}, expected {:?}", a.dims, dims),
            });
        }
        Ok(&a.data)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> ModelFile {
        let mut m = ModelFile::new("segmenter", 3);
        m.push("colour", &[2, 3], vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        m.push("weights", &[5], vec![1.5; 5]);
        m
    }

    #[test]
    fn round_trip() {
        let m = sample();
        let back =
            ModelFile::decode(&m.encode(), Path::new("m.bin"), "segmenter", 3).expect("decodes");
        assert_eq!(back, m);
        assert_eq!(
            back.array(Path::new("m.bin"), "colour", &[2, 3])
                .expect("present")[4],
            4.0
        );
        let err = back
            .array(Path::new("m.bin"), "colour", &[3, 2])
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("m.bin") && err.contains("colour") && err.contains("shape"),
            "{err}"
        );
    }

    #[test]
    fn every_truncation_is_an_error_not_a_panic() {
        let bytes = sample().encode();
        for n in 0..bytes.len() {
            assert!(
                ModelFile::decode(&bytes[..n], Path::new("m.bin"), "segmenter", 3).is_err(),
                "prefix {n}"
            );
        }
    }

    #[test]
    fn corruption_kind_and_version_are_named() {
        let mut bytes = sample().encode();
        let p = Path::new("m.bin");
        assert!(matches!(
            ModelFile::decode(&bytes, p, "codebook", 3),
            Err(ModelError::Kind { .. })
        ));
        assert!(matches!(
            ModelFile::decode(&bytes, p, "segmenter", 4),
            Err(ModelError::Version { found: 3, .. })
        ));
        let k = bytes.len() - 12;
        bytes[k] ^= 0x55;
        assert!(matches!(
            ModelFile::decode(&bytes, p, "segmenter", 3),
            Err(ModelError::Corrupt { .. })
        ));
        assert!(matches!(
            ModelFile::decode(b"PNG", p, "segmenter", 3),
            Err(ModelError::Magic { .. })
        ));
        let err =
            ModelFile::read(Path::new("/nonexistent/segmenter.bin"), "segmenter", 3).unwrap_err();
        assert!(
            matches!(err, ModelError::Missing { .. })
                && err.to_string().contains("/nonexistent/segmenter.bin")
        );
    }
}
