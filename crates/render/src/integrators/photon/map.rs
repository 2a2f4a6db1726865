//! Photon maps: photons in a k-d tree (the `kiddo` crate, built from the photons in
//! emission order) and the radiance estimates read from them.

use std::num::NonZero;

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use super::{Kernel, Lookup};
use crate::bsdf::{Bsdf, TransportMode};
use crate::geometry::Ray;
use crate::integrators::photons::PhotonHit;
use crate::integrators::transport::Scatterer;
use crate::math::{Frame, INV_PI, PI, Vec2, Vec3};
use crate::media::Phase;
use crate::sampling::warp::square_to_uniform_sphere;
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

/// K(d) for squared distance `d2` within radius² `r2`, normalised over the disk.
fn kernel_weight(kernel: Kernel, d2: f32, r2: f32) -> f32 {
    let base = 1.0 / (PI * r2);
    match kernel {
        Kernel::Box => base,
        Kernel::Cone => 3.0 * (1.0 - (d2 / r2).sqrt()).max(0.0) * base,
        Kernel::Epanechnikov => 2.0 * (1.0 - d2 / r2).max(0.0) * base,
    }
}

/// What a map keeps of a photon besides its position.
#[derive(Clone, Copy, Debug)]
pub struct StoredPhoton<C = Vec3> {
    /// Towards where it came from.
    pub wi: Vec3,
    pub beta: C,
    /// Edges from the light.
    pub edges: u32,
    /// Its secondary wavelengths were terminated (spectral mode).
    pub terminated: bool,
}

/// Bytes per stored photon of colour `C`: its position in the tree (12), the tree's index (4)
/// and a [`StoredPhoton`].
#[cfg(test)]
fn bytes_per_photon<C>() -> u64 {
    16 + std::mem::size_of::<StoredPhoton<C>>() as u64
}

/// Every this many photons of a surface map (in emission order within a tracing chunk) get a
/// precomputed estimate when the map serves final gathering ([`Irradiance`]).
pub const RADIANCE_STRIDE: usize = 16;

/// Normals agree when their cosine is at least this (about 25°; Christensen's 0.9).
const NORMALS_AGREE: f32 = 0.9;

/// A precomputed estimate at a photon's position (Christensen 1999's radiance photon).
#[derive(Clone, Copy)]
struct RadiancePhoton<C> {
    /// The shading normal where the photon hit.
    n: Vec3,
    /// The squared radius of the region its estimate read.
    r2: f32,
    /// Σ K·β over the photons found around it that arrive on `n`'s side ([0]) and on the
    /// other ([1]): the irradiance of either side times N.
    e: [Estimate<C>; 2],
}

/// Precomputed estimates at a subset of a surface map's photons (Christensen 1999, "Faster
/// photon map global illumination"; pbrt-v2's radiance photons): at a diffuse surface, where
/// f is constant over each hemisphere, the exact estimate Σ K·f·β is f times the irradiance
/// sum of wo's side, which the nearest precomputed one stands for (one nearest-neighbour
/// query instead of k, and no BSDF evaluation per photon). See [`PhotonMap::precomputed`].
struct Irradiance<C> {
    tree: ImmutableKdTree<f32, 3>,
    at: Vec<RadiancePhoton<C>>,
    /// The most edges of the photons the sums hold (those that fit the budget they were
    /// precomputed for, [`PhotonMap::precompute`]), and the fewest of the others (`None`:
    /// every photon fits): the sums serve a vertex whose budget admits the same photons.
    edges: u32,
    next: Option<u32>,
}

/// A photon map.
pub struct PhotonMap<C = Vec3> {
    tree: ImmutableKdTree<f32, 3>,
    photons: Vec<StoredPhoton<C>>,
    /// The photons' positions, kept for a volume map alone ([`Enclosure`]; 12 bytes more per
    /// photon in a medium, within [`super::memory_needed`]'s bound).
    points: Vec<[f32; 3]>,
    /// Up to 1024 photon positions spread evenly over the emission order
    /// ([`PhotonMap::resolve`]).
    sample: Vec<[f32; 3]>,
    /// Precomputed estimates for final gathering (surface maps that serve it).
    irradiance: Option<Irradiance<C>>,
}

impl<C: Color> PhotonMap<C> {
    fn new(
        points: Vec<[f32; 3]>,
        photons: Vec<StoredPhoton<C>>,
        keep_points: bool,
    ) -> Option<PhotonMap<C>> {
        if points.is_empty() {
            return None;
        }
        let tree = ImmutableKdTree::new_from_slice(&points).ok()?;
        let n = points.len();
        let m = n.min(1024);
        let sample = (0..m).map(|i| points[i * n / m]).collect();
        Some(PhotonMap {
            tree,
            photons,
            points: if keep_points { points } else { Vec::new() },
            sample,
            irradiance: None,
        })
    }

    /// Precompute the estimates (read with `lookup` and `kernel`, of the photons whose path
    /// fits in `budget` edges) at the photons `marked` (their index and shading normal), in
    /// parallel on the current rayon pool.
    pub fn precompute(
        &mut self,
        (lookup, kernel): (Lookup, Kernel),
        budget: Option<u32>,
        marked: &[(u32, Vec3)],
    ) {
        use rayon::prelude::*;
        let at: Vec<([f32; 3], RadiancePhoton<C>)> = marked
            .par_iter()
            .filter_map(|&(i, n)| {
                let q = self.tree_point(i as usize)?;
                let mut e = [Estimate([C::ZERO; 2]); 2];
                let r2 = self.visit(
                    lookup,
                    Vec3::new(q[0], q[1], q[2]),
                    budget,
                    |ph, _, d2, r2| {
                        let c = n.dot(ph.wi);
                        if c != 0.0 {
                            let side = &mut e[(c < 0.0) as usize].0[ph.terminated as usize];
                            *side += ph.beta * kernel_weight(kernel, d2, r2);
                        }
                    },
                );
                Some((q, RadiancePhoton { n, r2, e }))
            })
            .collect();
        let points: Vec<[f32; 3]> = at.iter().map(|(q, _)| *q).collect();
        let Ok(tree) = ImmutableKdTree::new_from_slice(&points) else {
            return;
        };
        self.irradiance = Some(Irradiance {
            tree,
            at: at.into_iter().map(|(_, rp)| rp).collect(),
            edges: (self.photons.iter().map(|p| p.edges))
                .filter(|&e| budget.is_none_or(|b| e <= b))
                .max()
                .unwrap_or(0),
            next: (self.photons.iter().map(|p| p.edges))
                .filter(|&e| budget.is_some_and(|b| e > b))
                .min(),
        });
    }

    /// Photon `i`'s position, from the positions kept for precomputation.
    fn tree_point(&self, i: usize) -> Option<[f32; 3]> {
        self.points.get(i).copied()
    }

    /// The precomputed estimate standing for [`PhotonMap::surface_estimate`]'s at `p`, or
    /// `None` where it does not serve: a BSDF other than diffuse, a `budget` that some photon
    /// exceeds, no precomputed estimate whose region holds `p` with a normal agreeing with
    /// the frame's (either way round: the other side's sum when they face apart). Its bias:
    /// the estimate of the nearest marked photon y instead of p's, both read from the same
    /// photons' density — a further blur of at most one lookup radius, correlated over a
    /// cell of the marked photons' Voronoi diagram.
    pub(super) fn precomputed(
        &self,
        p: Vec3,
        (bsdf, frame, wo): (&Bsdf<C>, &Frame, Vec3),
        budget: Option<u32>,
    ) -> Option<Estimate<C>> {
        let irr = self.irradiance.as_ref()?;
        let Bsdf::Diffuse(d) = bsdf else { return None };
        // The photons `budget` admits must be those the sums hold.
        let fits = match budget {
            None => irr.next.is_none(),
            Some(b) => b >= irr.edges && irr.next.is_none_or(|n| b < n),
        };
        if !fits {
            return None;
        }
        if wo.z <= 0.0 {
            return Some(Estimate([C::ZERO; 2]));
        }
        let nn = irr
            .tree
            .query(&[p.x, p.y, p.z])
            .nearest_one::<SquaredEuclidean<f32>>()
            .execute();
        let rp = irr.at.get(nn.item as usize)?;
        if nn.distance > rp.r2 {
            return None;
        }
        let c = frame.n.dot(rp.n);
        let side = if c >= NORMALS_AGREE {
            0
        } else if c <= -NORMALS_AGREE {
            1
        } else {
            return None;
        };
        Some(rp.e[side].times(d.reflectance * INV_PI))
    }

    /// Photons stored.
    pub fn len(&self) -> usize {
        self.photons.len()
    }

    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// `lookup` with a [`Lookup::Calibrated`] cap chosen from this map (from its sample of
    /// photons: deterministic).
    pub fn resolve(&self, lookup: Lookup) -> Lookup {
        let Lookup::Calibrated { k } = lookup else {
            return lookup;
        };
        // The photon itself is its own nearest neighbour: k + 1.
        let kk = NonZero::new(k.max(1) as usize + 1).unwrap_or(NonZero::<usize>::MIN);
        let mut d2: Vec<f32> = (self.sample.iter())
            .filter_map(|q| {
                let found = self
                    .tree
                    .query(q)
                    .nearest_n::<SquaredEuclidean<f32>>(kk)
                    .execute();
                (found.len() == kk.get()).then(|| found[kk.get() - 1].distance)
            })
            .filter(|d| d.is_finite() && *d > 0.0)
            .collect();
        if d2.is_empty() {
            return Lookup::Nearest {
                k,
                max_radius: f32::INFINITY,
            };
        }
        let quarter = d2.len() / 4;
        let (_, quartile, _) = d2.select_nth_unstable_by(quarter, f32::total_cmp);
        Lookup::Nearest {
            k,
            max_radius: quartile.sqrt(),
        }
    }

    /// Calls `each`(photon, its index, d², r²) for the photons `lookup` finds around `p`
    /// whose path fits in `budget` edges, r the radius of the region searched (found
    /// unsorted: only the farthest distance matters); returns r² (0: none).
    fn visit(
        &self,
        lookup: Lookup,
        p: Vec3,
        budget: Option<u32>,
        mut each: impl FnMut(&StoredPhoton<C>, usize, f32, f32),
    ) -> f32 {
        let q = [p.x, p.y, p.z];
        let (found, r2) = match lookup {
            Lookup::Radius(r) => {
                let found = self
                    .tree
                    .query(&q)
                    .within::<SquaredEuclidean<f32>>(r * r)
                    .unsorted()
                    .execute();
                (found, r * r)
            }
            Lookup::Nearest { k, .. } | Lookup::Calibrated { k } => {
                // (`Calibrated` is resolved by `PhotonMap::resolve`; unresolved, k nearest.)
                let max_radius = match lookup {
                    Lookup::Nearest { max_radius, .. } => max_radius,
                    _ => f32::INFINITY,
                };
                let k = NonZero::new(k.max(1) as usize).unwrap_or(NonZero::<usize>::MIN);
                let found = if max_radius.is_finite() {
                    self.tree
                        .query(&q)
                        .nearest_n::<SquaredEuclidean<f32>>(k)
                        .within(max_radius * max_radius)
                        .unsorted()
                        .execute()
                } else {
                    self.tree
                        .query(&q)
                        .nearest_n::<SquaredEuclidean<f32>>(k)
                        .unsorted()
                        .execute()
                };
                // The radius of the region the photons were found in: the k-th distance, or
                // the cap when fewer were found within it.
                let r2 = if found.len() == k.get() || !max_radius.is_finite() {
                    found.iter().map(|n| n.distance).fold(0.0, f32::max)
                } else {
                    max_radius * max_radius
                };
                (found, r2)
            }
        };
        if r2.is_nan() || r2 <= 0.0 {
            return 0.0;
        }
        for n in &found {
            let i = n.item as usize;
            let ph = &self.photons[i];
            if budget.is_some_and(|b| ph.edges > b) {
                continue;
            }
            each(ph, i, n.distance, r2);
        }
        r2
    }

    /// Σ `term`(photon, its index, d², r²) over the photons [`PhotonMap::visit`] finds:
    /// [photons whose wavelengths are all live, photons that terminated their secondaries]
    /// (spectral mode; see [`Estimate`]), and r².
    fn sum(
        &self,
        lookup: Lookup,
        p: Vec3,
        budget: Option<u32>,
        term: impl Fn(&StoredPhoton<C>, usize, f32, f32) -> C,
    ) -> (Estimate<C>, f32) {
        let mut sum = Estimate([C::ZERO; 2]);
        let r2 = self.visit(lookup, p, budget, |ph, i, d2, r2| {
            sum.0[ph.terminated as usize] += term(ph, i, d2, r2);
        });
        (sum, r2)
    }

    /// Σ K·β and Σ (K·β)² over the photons `lookup` finds around `p`: N times the
    /// irradiance estimate there (of photons of every depth) and what its variance is
    /// estimated from (tests of the density estimation).
    pub fn irradiance_sums(&self, lookup: Lookup, kernel: Kernel, p: Vec3) -> (C, C) {
        let sq = std::cell::Cell::new(C::ZERO);
        let (Estimate([live, terminated]), _) = self.sum(lookup, p, None, |ph, _, d2, r2| {
            let c = ph.beta * kernel_weight(kernel, d2, r2);
            sq.set(sq.get() + c * c);
            c
        });
        (live + terminated, sq.get())
    }

    /// The estimate at a surface vertex scattering by `bsdf` in `frame` towards `wo`, not
    /// yet divided by the number of photons emitted: Σ K·f·β over the photons around `p`
    /// (f without its cosine: the photon's power holds it).
    pub(super) fn surface_estimate(
        &self,
        lookup: Lookup,
        kernel: Kernel,
        p: Vec3,
        (bsdf, frame, wo): (&Bsdf<C>, &Frame, Vec3),
        budget: Option<u32>,
    ) -> Estimate<C> {
        if let Bsdf::Diffuse(d) = bsdf {
            // f = R/π on the front side for both directions, else 0: one product.
            if wo.z <= 0.0 {
                return Estimate([C::ZERO; 2]);
            }
            let (sum, _) = self.sum(lookup, p, budget, |ph, _, d2, r2| {
                if frame.n.dot(ph.wi) > 0.0 {
                    ph.beta * kernel_weight(kernel, d2, r2)
                } else {
                    C::ZERO
                }
            });
            return sum.times(d.reflectance * INV_PI);
        }
        let (sum, _) = self.sum(lookup, p, budget, |ph, _, d2, r2| {
            let wl = frame.to_local(ph.wi);
            if wl.z == 0.0 {
                return C::ZERO;
            }
            let f = bsdf.eval(wo, wl, TransportMode::Radiance) / wl.z.abs();
            f * ph.beta * kernel_weight(kernel, d2, r2)
        });
        sum
    }

    /// The estimate at a collision in a medium at `around.p`, scattering by `phase` towards
    /// `wo`, not yet divided by the number of photons emitted: σs times the in-scattered
    /// radiance, Σ p(wo, wᵢ)·β / V over the photons found in the part of the ball searched
    /// that the point sees (V its volume, [`Enclosure`]; the kernel does not apply there).
    pub(super) fn volume_estimate(
        &self,
        lookup: Lookup,
        around: &Enclosure,
        (phase, wo): (&Phase, Vec3),
        budget: Option<u32>,
    ) -> Estimate<C> {
        let (sum, r2) = self.sum(lookup, around.p, budget, |ph, i, d2, _| {
            if around.hides(self.points[i], d2) {
                return C::ZERO;
            }
            ph.beta * phase.eval(wo, ph.wi)
        });
        let v = 4.0 / 3.0 * PI * r2 * r2.sqrt() * around.fraction(r2.sqrt());
        if v > 0.0 {
            sum.scaled(1.0 / v)
        } else {
            Estimate([C::ZERO; 2])
        }
    }
}

/// Bands of equal height in z, of [`Enclosure`], each cut into four quadrants in φ: 16 cells
/// of equal solid angle (Archimedes).
const BANDS: usize = 4;
const CELLS: usize = BANDS * 4;

/// The part of a ball around a point `p` in a medium that `p` sees, for volume estimates
/// near the medium's boundary: photons deposit only where the medium is, so a ball reaching
/// past a boundary (a null surface, an object inside the medium) holds fewer photons than
/// its volume says, and the estimate darkens towards every edge of a medium. The sphere of
/// directions, in a frame turned at random, is cut into 16 cells of equal solid angle, and
/// one ray per cell (through its middle) finds the distance t to the first surface there.
/// The estimate counts a photon only if it is nearer than its cell's t, and divides by the
/// volume of the same star-shaped region, Σ (4π/16)·min(r, t)³/3: a consistent estimate of
/// the density inside it, which tends to the medium's region around `p` as r shrinks.
pub struct Enclosure {
    p: Vec3,
    frame: Frame,
    /// Per cell, the distance to the first surface, at most the reach probed.
    t: [f32; CELLS],
    /// The least of `t`: nothing nearer is hidden.
    open: f32,
}

impl Enclosure {
    /// Probe around `p` up to `reach` (the lookup's largest radius), the cells turned by the
    /// uniform numbers `u`.
    pub fn probe(scene: &Scene, p: Vec3, reach: f32, u: [f32; 3]) -> Enclosure {
        let f = Frame::from_normal(square_to_uniform_sphere(Vec2::new(u[0], u[1])));
        let (sin, cos) = (2.0 * PI * u[2]).sin_cos();
        let frame = Frame {
            s: f.s * cos + f.t * sin,
            t: f.t * cos - f.s * sin,
            n: f.n,
        };
        let mut t = [reach; CELLS];
        for (cell, t) in t.iter_mut().enumerate() {
            let z = -1.0 + ((cell / 4) as f32 + 0.5) * (2.0 / BANDS as f32);
            let r = (1.0 - z * z).sqrt() * std::f32::consts::FRAC_1_SQRT_2;
            let (x, y) = match cell % 4 {
                0 => (r, r),
                1 => (-r, r),
                2 => (-r, -r),
                _ => (r, -r),
            };
            let d = frame.to_world(Vec3::new(x, y, z));
            if let Some(hit) = scene.accel.intersect(&Ray::new(p, d), reach) {
                *t = hit.t;
            }
        }
        let open = t.iter().copied().fold(reach, f32::min);
        Enclosure { p, frame, t, open }
    }

    /// Whether a photon at `q`, `d2` squared away, lies past its cell's first surface.
    fn hides(&self, q: [f32; 3], d2: f32) -> bool {
        if d2 <= self.open * self.open {
            return false;
        }
        let l = self.frame.to_local(Vec3::new(q[0], q[1], q[2]) - self.p);
        let band = (((l.z * d2.sqrt().recip() + 1.0) * 0.5 * BANDS as f32) as usize).min(BANDS - 1);
        let quadrant = match (l.x > 0.0, l.y > 0.0) {
            (true, true) => 0,
            (false, true) => 1,
            (false, false) => 2,
            (true, false) => 3,
        };
        let t = self.t[band * 4 + quadrant];
        d2 > t * t
    }

    /// The region's share of the ball of radius `r`.
    pub fn fraction(&self, r: f32) -> f32 {
        if self.open >= r {
            return 1.0;
        }
        let sum: f32 = self.t.iter().map(|&t| (t / r).min(1.0).powi(3)).sum();
        sum / CELLS as f32
    }
}

/// A radiance estimate from a map, not yet times the camera path's throughput: the sums
/// over the photons whose wavelengths were all live and over those that had terminated
/// their secondaries (always 0 in RGB mode). A contribution (camera throughput × photon
/// term) counts with every wavelength only when both paths kept theirs, else with the
/// hero's alone, so [`Estimate::to_rgb`] converts at the camera vertex, with the camera
/// path's mode as it is there.
#[derive(Clone, Copy)]
pub(super) struct Estimate<C>([C; 2]);

impl<C: Color> Estimate<C> {
    fn scaled(self, s: f32) -> Estimate<C> {
        Estimate(self.0.map(|c| c * s))
    }

    fn times(self, c: C) -> Estimate<C> {
        Estimate(self.0.map(|e| e * c))
    }

    /// `beta` (the camera path's throughput) times the estimate, as linear sRGB for the
    /// camera path's mode `m`.
    pub(super) fn to_rgb<M: PathMode<C = C>>(self, beta: C, m: &M) -> Vec3 {
        let [live, terminated] = self.0;
        if m.terminated() {
            m.to_rgb(beta * (live + terminated))
        } else if terminated.is_black() {
            m.to_rgb(beta * live)
        } else {
            m.to_rgb(beta * live) + m.terminate().to_rgb(beta * terminated)
        }
    }
}

/// Photons gathered for one map, in emission order.
pub(super) struct MapData<C> {
    points: Vec<[f32; 3]>,
    photons: Vec<StoredPhoton<C>>,
    /// Every [`RADIANCE_STRIDE`]th surface photon's index and shading normal.
    marked: Vec<(u32, Vec3)>,
}

impl<C> Default for MapData<C> {
    fn default() -> Self {
        MapData {
            points: Vec::new(),
            photons: Vec::new(),
            marked: Vec::new(),
        }
    }
}

impl<C: Color> MapData<C> {
    /// Store `hit`, carried by a photon now in mode `m`.
    pub(super) fn push<M: PathMode<C = C>>(&mut self, hit: &PhotonHit<C>, m: &M) {
        let p = hit.v.p;
        if let Scatterer::Surface { frame, .. } = hit.v.at
            && self.points.len().is_multiple_of(RADIANCE_STRIDE)
        {
            self.marked.push((self.points.len() as u32, frame.n));
        }
        self.points.push([p.x, p.y, p.z]);
        self.photons.push(StoredPhoton {
            wi: hit.wi,
            beta: hit.v.beta,
            edges: hit.v.depth,
            terminated: m.terminated(),
        });
    }

    pub(super) fn append(&mut self, mut other: MapData<C>) {
        let offset = self.points.len() as u32;
        (self.marked).extend(other.marked.iter().map(|&(i, n)| (i + offset, n)));
        self.points.append(&mut other.points);
        self.photons.append(&mut other.photons);
    }

    /// The map; `volume`: a volume map, which keeps its photons' positions; `precompute`:
    /// the lookup and kernel of the estimates to precompute at the marked photons, and the
    /// budget of the photons they hold.
    pub(super) fn build(
        self,
        volume: bool,
        precompute: Option<((Lookup, Kernel), Option<u32>)>,
    ) -> Option<PhotonMap<C>> {
        let keep = volume || precompute.is_some();
        let mut map = PhotonMap::new(self.points, self.photons, keep)?;
        if let Some((read, budget)) = precompute {
            map.precompute(read, budget, &self.marked);
            if !volume {
                map.points = Vec::new();
            }
        }
        Some(map)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::SampledSpectrum;

    use super::super::BYTES_PER_PHOTON;
    /// The memory per photon the docs state is what a stored photon takes.
    #[test]
    fn bytes_per_photon_as_documented() {
        assert_eq!(bytes_per_photon::<Vec3>(), BYTES_PER_PHOTON);
        assert_eq!(bytes_per_photon::<SampledSpectrum>(), BYTES_PER_PHOTON);
    }

    /// On a cubic lattice of spacing 1 the 6 nearest neighbours of an inner photon are at
    /// distance 1 and the 7th at √2: the calibrated cap for k = 6 is 1 (most sampled photons
    /// are inner ones), and for k = 7, √2.
    #[test]
    fn calibrated_cap_is_the_lower_quartile_of_kth_distances() {
        let n = 20;
        let mut points = Vec::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    points.push([x as f32, y as f32, z as f32]);
                }
            }
        }
        let photons = vec![
            StoredPhoton {
                wi: Vec3::Z,
                beta: Vec3::ONE,
                edges: 1,
                terminated: false,
            };
            points.len()
        ];
        let map = PhotonMap::new(points, photons, false).unwrap();
        for (k, want) in [(6, 1.0f32), (7, 2.0f32.sqrt())] {
            match map.resolve(Lookup::Calibrated { k }) {
                Lookup::Nearest {
                    k: got_k,
                    max_radius,
                } => {
                    assert_eq!(got_k, k);
                    assert!((max_radius - want).abs() < 1e-5, "k = {k}: {max_radius}");
                }
                other => panic!("{other:?}"),
            }
        }
        // Other lookups pass through.
        let r = Lookup::Radius(0.5);
        assert_eq!(map.resolve(r), r);
    }

    /// A small deterministic generator for the tests (SplitMix64).
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> f32 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// A map of `n` photons spread uniformly over the unit square of the plane z = 0, of
    /// power growing along x, arriving from the front (z > 0) seven times in ten, terminated
    /// three times in ten, its estimates precomputed at every 16th.
    fn plane_map(n: usize, rng: &mut Rng, lookup: Lookup) -> PhotonMap<Vec3> {
        let mut points = Vec::new();
        let mut photons = Vec::new();
        for _ in 0..n {
            let (x, y) = (rng.next(), rng.next());
            points.push([x, y, 0.0]);
            let z = if rng.next() < 0.7 { 0.6 } else { -0.6 };
            photons.push(StoredPhoton {
                wi: Vec3::new(0.8, 0.0, z),
                beta: Vec3::new(1.0 + x, 2.0, 3.0 - x),
                edges: 1 + (rng.next() * 4.0) as u32,
                terminated: rng.next() < 0.3,
            });
        }
        let marked: Vec<(u32, Vec3)> = (0..n)
            .step_by(RADIANCE_STRIDE)
            .map(|i| (i as u32, Vec3::Z))
            .collect();
        let mut map = PhotonMap::new(points, photons, true).unwrap();
        map.precompute((lookup, Kernel::Box), None, &marked);
        map
    }

    /// The precomputed estimates (radiance photons) equal the direct ones in expectation: over
    /// `MAPS` independent maps (fixed seeds), the mean over 256 query points in the middle
    /// of the square of precomputed − direct, for either side of the plane (the frame's
    /// normal +z, and −z: a two-sided surface seen from the back) and either part of the
    /// estimate (live, terminated), is z-tested against 0. Significance: 4 tests,
    /// Šidák-corrected to α = 0.01 overall, with the t distribution of 39 degrees of
    /// freedom: |t| < 3.25 each. Also: the direct estimate at a diffuse surface is f times
    /// the irradiance sum of wo's side, and a budget some photon exceeds, or a glossy BSDF,
    /// falls back to the direct estimate.
    #[test]
    fn precomputed_photon_estimates_match_the_direct_ones() {
        const MAPS: usize = 40;
        let lookup = Lookup::Nearest {
            k: 64,
            max_radius: f32::INFINITY,
        };
        let bsdf = Bsdf::Diffuse(crate::bsdf::Diffuse::new(Vec3::new(0.5, 0.6, 0.7)));
        let frames = [Frame::from_normal(Vec3::Z), Frame::from_normal(-Vec3::Z)];
        let wo = Vec3::new(0.0, 0.0, 1.0);
        let mut rng = Rng(7);
        // Per map, per (side, part): the mean difference (lanes summed).
        let mut diffs = vec![[0.0f64; 4]; MAPS];
        let mut served = 0usize;
        for diff in diffs.iter_mut() {
            let map = plane_map(20_000, &mut rng, lookup);
            for _ in 0..256 {
                let p = Vec3::new(0.3 + 0.4 * rng.next(), 0.3 + 0.4 * rng.next(), 0.0);
                for (side, frame) in frames.iter().enumerate() {
                    let direct =
                        map.surface_estimate(lookup, Kernel::Box, p, (&bsdf, frame, wo), None);
                    let Some(pre) = map.precomputed(p, (&bsdf, frame, wo), None) else {
                        continue;
                    };
                    served += 1;
                    for part in 0..2 {
                        let d = pre.0[part] - direct.0[part];
                        diff[side * 2 + part] += (d.x + d.y + d.z) as f64 / 256.0;
                    }
                    // Budgets: the photons have up to 4 edges.
                    assert!(map.precomputed(p, (&bsdf, frame, wo), Some(3)).is_none());
                    assert!(map.precomputed(p, (&bsdf, frame, wo), Some(4)).is_some());
                }
            }
        }
        // Most queries are served (the rest fall back: no region holds them).
        assert!(served > MAPS * 256 * 2 * 9 / 10, "served {served}");
        for t in 0..4 {
            let xs: Vec<f64> = diffs.iter().map(|d| d[t]).collect();
            let mean = xs.iter().sum::<f64>() / MAPS as f64;
            let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (MAPS - 1) as f64;
            let z = mean / (var / MAPS as f64).sqrt();
            assert!(
                var > 0.0 && z.abs() < 3.25,
                "side/part {t}: mean {mean}, z {z}"
            );
        }
        // A BSDF other than diffuse is not served.
        let map = plane_map(2_000, &mut rng, lookup);
        let glossy = Bsdf::Conductor(crate::bsdf::Conductor::new(Vec3::ONE, Vec3::ONE, Vec3::ONE));
        let p = Vec3::new(0.5, 0.5, 0.0);
        assert!(
            map.precomputed(p, (&glossy, &frames[0], wo), None)
                .is_none()
        );
    }
}
