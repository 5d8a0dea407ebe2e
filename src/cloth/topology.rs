//! Triangle-mesh topology for garments: unique edges, hinges, boundary loops, adjacency.
//!
//! Everything here is computed by sorting (never by iterating a hash map), so the same triangles
//! always give the same lists in the same order. The garment generator uses [`boundary_loops`] to
//! find the armholes its sleeves are welded to and the neckline it anchors; the solver builds its
//! stretch constraints from [`unique_edges`], its bending constraints from [`hinges`] and its
//! tethers' geodesic distances from [`Adjacency`].

/// Every undirected edge once, as `[low, high]`, sorted.
pub fn unique_edges(triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut edges: Vec<[u32; 2]> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])].map(|(a, b)| [a.min(b), a.max(b)]))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// Interior edges shared by exactly two triangles, as `[shared₀, shared₁, opposite₀, opposite₁]`
/// where `opposite₀` belongs to the triangle in which the edge runs `shared₀ → shared₁`.
pub fn hinges(triangles: &[[u32; 3]]) -> Vec<[u32; 4]> {
    // (low, high, opposite, forward?) per triangle edge.
    let mut half: Vec<(u32, u32, u32, bool)> = Vec::with_capacity(triangles.len() * 3);
    for t in triangles {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            half.push((a.min(b), a.max(b), c, a < b));
        }
    }
    half.sort_unstable();
    let mut out = Vec::new();
    let mut i = 0;
    while i < half.len() {
        let mut j = i + 1;
        while j < half.len() && half[j].0 == half[i].0 && half[j].1 == half[i].1 {
            j += 1;
        }
        if j - i == 2 && half[i].2 != half[i + 1].2 {
            let (lo, hi) = (half[i].0, half[i].1);
            // Orient the hinge along the first triangle's direction.
            let (first, second) = if half[i].3 {
                (half[i], half[i + 1])
            } else {
                (half[i + 1], half[i])
            };
            if first.3 {
                out.push([lo, hi, first.2, second.2]);
            } else {
                out.push([hi, lo, first.2, second.2]);
            }
        }
        i = j;
    }
    out
}

/// Closed boundary loops, each following the boundary edges in the direction the triangles run them.
/// Loops start at their smallest vertex index and are listed by that index.
pub fn boundary_loops(triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut directed: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    directed.sort_unstable();
    let mut boundary: Vec<(u32, u32)> = directed
        .iter()
        .copied()
        .filter(|&(a, b)| directed.binary_search(&(b, a)).is_err())
        .collect();
    boundary.dedup();
    let mut used = vec![false; boundary.len()];
    let mut loops = Vec::new();
    for start in 0..boundary.len() {
        if used[start] {
            continue;
        }
        let mut chain = Vec::new();
        let mut current = start;
        loop {
            used[current] = true;
            let (from, to) = boundary[current];
            chain.push(from);
            // Next unused boundary edge leaving `to`.
            let first = boundary.partition_point(|e| e.0 < to);
            let next = (first..boundary.len())
                .take_while(|&k| boundary[k].0 == to)
                .find(|&k| !used[k]);
            match next {
                Some(k) => current = k,
                None => break,
            }
        }
        loops.push(chain);
    }
    loops
}

/// Does every edge shared by two triangles run in opposite directions in them (consistent winding)?
pub fn consistently_wound(triangles: &[[u32; 3]]) -> bool {
    let mut directed: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    directed.sort_unstable();
    directed.windows(2).all(|w| w[0] != w[1])
}

/// Vertex adjacency over the mesh edges (compressed rows): each vertex's neighbours, and beside
/// them the indices of the edges that lead there.
#[derive(Clone, Debug, PartialEq)]
pub struct Adjacency {
    offsets: Vec<u32>,
    neighbours: Vec<u32>,
    /// Per entry of `neighbours`: the index, in the edge list given to [`Adjacency::new`], of the
    /// edge to that neighbour.
    edges: Vec<u32>,
}

impl Adjacency {
    pub fn new(vertex_count: usize, edges: &[[u32; 2]]) -> Adjacency {
        let mut degree = vec![0u32; vertex_count + 1];
        for e in edges {
            for v in e {
                if let Some(d) = degree.get_mut(*v as usize + 1) {
                    *d += 1;
                }
            }
        }
        for k in 1..degree.len() {
            degree[k] += degree[k - 1];
        }
        let offsets = degree;
        let mut fill = offsets.clone();
        let mut neighbours = vec![0u32; offsets[vertex_count] as usize];
        let mut edge_of = vec![0u32; neighbours.len()];
        for (k, &[a, b]) in edges.iter().enumerate() {
            if (a as usize) < vertex_count && (b as usize) < vertex_count {
                for (v, other) in [(a, b), (b, a)] {
                    let slot = fill[v as usize] as usize;
                    neighbours[slot] = other;
                    edge_of[slot] = k as u32;
                    fill[v as usize] += 1;
                }
            }
        }
        Adjacency {
            offsets,
            neighbours,
            edges: edge_of,
        }
    }

    pub fn neighbours(&self, v: usize) -> &[u32] {
        &self.neighbours[self.row(v)]
    }

    /// The indices of vertex `v`'s edges in the edge list the adjacency was built from, in the
    /// order of [`Adjacency::neighbours`].
    pub fn edges(&self, v: usize) -> &[u32] {
        &self.edges[self.row(v)]
    }

    fn row(&self, v: usize) -> std::ops::Range<usize> {
        match (self.offsets.get(v), self.offsets.get(v + 1)) {
            (Some(&a), Some(&b)) => a as usize..b as usize,
            _ => 0..0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles forming the unit square 0-1-2-3, counter-clockwise.
    fn square() -> Vec<[u32; 3]> {
        vec![[0, 1, 2], [0, 2, 3]]
    }

    #[test]
    fn square_topology() {
        let t = square();
        assert_eq!(
            unique_edges(&t),
            vec![[0, 1], [0, 2], [0, 3], [1, 2], [2, 3]]
        );
        // The diagonal 0–2 runs 2 → 0 in the first triangle and 0 → 2 in the second.
        assert_eq!(hinges(&t), vec![[0, 2, 3, 1]]);
        assert_eq!(boundary_loops(&t), vec![vec![0, 1, 2, 3]]);
        assert!(consistently_wound(&t));
        assert!(!consistently_wound(&[[0, 1, 2], [0, 3, 2]]));
        let adjacency = Adjacency::new(4, &unique_edges(&t));
        assert_eq!(adjacency.neighbours(0), &[1, 2, 3]);
        assert_eq!(adjacency.neighbours(1), &[0, 2]);
        assert!(adjacency.neighbours(9).is_empty());
        // Edges [0,1] [0,2] [0,3] [1,2] [2,3]: vertex 2's are 1 (to 0), 3 (to 1) and 4 (to 3).
        assert_eq!(adjacency.neighbours(2), &[0, 1, 3]);
        assert_eq!(adjacency.edges(2), &[1, 3, 4]);
        assert!(adjacency.edges(9).is_empty());
    }

    #[test]
    fn tube_has_two_loops() {
        // A 4-sided open tube: ring 0 = 0..4, ring 1 = 4..8.
        let mut t = Vec::new();
        for k in 0..4u32 {
            let (a, b) = (k, (k + 1) % 4);
            t.push([a, b + 4, b]);
            t.push([a, a + 4, b + 4]);
        }
        let loops = boundary_loops(&t);
        assert_eq!(loops.len(), 2);
        assert_eq!(loops[0].len(), 4);
        assert_eq!(loops[1].len(), 4);
        assert_eq!(hinges(&t).len(), 8);
    }
}
