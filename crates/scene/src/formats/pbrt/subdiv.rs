//! pbrt's `loopsubdiv` shape made into triangles at load time: `levels` rounds of Loop
//! subdivision (Loop 1987, with the boundary rules pbrt uses), then every vertex moved to its
//! limit position, with smooth normals averaged from the faces around it.

use std::collections::HashMap;

use glam::Vec3;

use super::params::{Params, Ty};
use crate::model::TriMesh;
use crate::{LoadError, Loc, Result};

/// Most triangles the subdivided mesh may have.
const MAX_TRIANGLES: usize = 1 << 22;

pub(super) fn loop_subdivide(p: &Params, levels: u32, loc: &Loc) -> Result<TriMesh> {
    let Some(pq) = p.nums("P", Ty::Point3)? else {
        return Err(LoadError::new(loc.clone(), "loopsubdiv needs \"point3 P\""));
    };
    let mut pos: Vec<Vec3> = pq
        .nums()
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
        .collect();
    let Some(iq) = p.nums("indices", Ty::Integer)? else {
        return Err(LoadError::new(
            loc.clone(),
            "loopsubdiv needs \"integer indices\"",
        ));
    };
    if iq.nums().len() % 3 != 0 {
        return Err(iq.err("indices are not a multiple of 3"));
    }
    let mut tris = Vec::with_capacity(iq.nums().len() / 3);
    for c in iq.nums().chunks_exact(3) {
        let mut t = [0u32; 3];
        for (k, &i) in c.iter().enumerate() {
            if i < 0.0 || i >= pos.len() as f64 {
                return Err(iq.err(format!("index {i} is outside the {} vertices", pos.len())));
            }
            t[k] = i as u32;
        }
        tris.push(t);
    }
    if tris.len().saturating_mul(4usize.saturating_pow(levels)) > MAX_TRIANGLES {
        return Err(LoadError::new(
            loc.clone(),
            format!("loopsubdiv: {levels} levels would make more than {MAX_TRIANGLES} triangles"),
        ));
    }
    for _ in 0..levels {
        (pos, tris) = subdivide(&pos, &tris);
    }
    let limit = limit_positions(&pos, &tris);
    let mut normals = vec![Vec3::ZERO; limit.len()];
    for &[a, b, c] in &tris {
        let n =
            (limit[b as usize] - limit[a as usize]).cross(limit[c as usize] - limit[a as usize]);
        for i in [a, b, c] {
            normals[i as usize] += n;
        }
    }
    let normals = normals.into_iter().map(Vec3::normalize_or_zero).collect();
    Ok(TriMesh {
        positions: limit,
        normals,
        uvs: Vec::new(),
        indices: tris,
    })
}

struct Topology {
    /// Each edge (smaller index first): the vertices opposite it in its faces.
    edges: HashMap<(u32, u32), Vec<u32>>,
    neighbours: Vec<Vec<u32>>,
    /// Neighbours across boundary edges (two for a boundary vertex).
    boundary: Vec<Vec<u32>>,
}

fn topology(n: usize, tris: &[[u32; 3]]) -> Topology {
    let mut edges: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for &[a, b, c] in tris {
        for (x, y, o) in [(a, b, c), (b, c, a), (c, a, b)] {
            edges.entry((x.min(y), x.max(y))).or_default().push(o);
        }
    }
    let mut neighbours = vec![Vec::new(); n];
    let mut boundary = vec![Vec::new(); n];
    for (&(a, b), opp) in &edges {
        neighbours[a as usize].push(b);
        neighbours[b as usize].push(a);
        if opp.len() == 1 {
            boundary[a as usize].push(b);
            boundary[b as usize].push(a);
        }
    }
    Topology {
        edges,
        neighbours,
        boundary,
    }
}

fn beta(n: usize) -> f32 {
    if n == 3 {
        3.0 / 16.0
    } else {
        3.0 / (8.0 * n as f32)
    }
}

fn subdivide(pos: &[Vec3], tris: &[[u32; 3]]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = topology(pos.len(), tris);
    let mut out: Vec<Vec3> = (0..pos.len())
        .map(|v| {
            let p = pos[v];
            let b = &t.boundary[v];
            if b.len() == 2 {
                0.75 * p + 0.125 * (pos[b[0] as usize] + pos[b[1] as usize])
            } else if b.is_empty() && !t.neighbours[v].is_empty() {
                let n = t.neighbours[v].len();
                let s: Vec3 = t.neighbours[v].iter().map(|&i| pos[i as usize]).sum();
                (1.0 - n as f32 * beta(n)) * p + beta(n) * s
            } else {
                p
            }
        })
        .collect();
    let mut edge_vertex: HashMap<(u32, u32), u32> = HashMap::with_capacity(t.edges.len());
    let mut keys: Vec<&(u32, u32)> = t.edges.keys().collect();
    keys.sort_unstable();
    for &(a, b) in keys {
        let opp = &t.edges[&(a, b)];
        let (pa, pb) = (pos[a as usize], pos[b as usize]);
        let q = if opp.len() == 2 {
            0.375 * (pa + pb) + 0.125 * (pos[opp[0] as usize] + pos[opp[1] as usize])
        } else {
            0.5 * (pa + pb)
        };
        edge_vertex.insert((a, b), out.len() as u32);
        out.push(q);
    }
    let e = |x: u32, y: u32| edge_vertex[&(x.min(y), x.max(y))];
    let mut new_tris = Vec::with_capacity(tris.len() * 4);
    for &[a, b, c] in tris {
        let (ab, bc, ca) = (e(a, b), e(b, c), e(c, a));
        new_tris.push([a, ab, ca]);
        new_tris.push([b, bc, ab]);
        new_tris.push([c, ca, bc]);
        new_tris.push([ab, bc, ca]);
    }
    (out, new_tris)
}

fn limit_positions(pos: &[Vec3], tris: &[[u32; 3]]) -> Vec<Vec3> {
    let t = topology(pos.len(), tris);
    (0..pos.len())
        .map(|v| {
            let p = pos[v];
            let b = &t.boundary[v];
            if b.len() == 2 {
                0.6 * p + 0.2 * (pos[b[0] as usize] + pos[b[1] as usize])
            } else if b.is_empty() && !t.neighbours[v].is_empty() {
                let n = t.neighbours[v].len();
                let g = 1.0 / (n as f32 + 3.0 / (8.0 * beta(n)));
                let s: Vec3 = t.neighbours[v].iter().map(|&i| pos[i as usize]).sum();
                (1.0 - n as f32 * g) * p + g * s
            } else {
                p
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_subdivided_tetrahedron_is_closed_and_shrinks_towards_a_sphere() {
        let pos = vec![
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(1.0, -1.0, -1.0),
        ];
        let tris = vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
        let (p, t) = subdivide(&pos, &tris);
        assert_eq!(t.len(), 16);
        assert_eq!(p.len(), 4 + 6);
        let topo = topology(p.len(), &t);
        assert!(topo.edges.values().all(|o| o.len() == 2), "closed");
        let l = limit_positions(&p, &t);
        for q in &l {
            assert!(q.length() < 3f32.sqrt());
        }
    }
}
