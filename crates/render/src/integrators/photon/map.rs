//! Photon maps: photons in a k-d tree (the `kiddo` crate, built from the photons in
//! emission order) and the radiance estimates read from them.

use std::num::NonZero;

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use super::{Kernel, Lookup};
use crate::bsdf::{Bsdf, TransportMode};
use crate::geometry::Ray;
use crate::integrators::photons::PhotonHit;
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
        })
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
}

impl<C> Default for MapData<C> {
    fn default() -> Self {
        MapData {
            points: Vec::new(),
            photons: Vec::new(),
        }
    }
}

impl<C: Color> MapData<C> {
    /// Store `hit`, carried by a photon now in mode `m`.
    pub(super) fn push<M: PathMode<C = C>>(&mut self, hit: &PhotonHit<C>, m: &M) {
        let p = hit.v.p;
        self.points.push([p.x, p.y, p.z]);
        self.photons.push(StoredPhoton {
            wi: hit.wi,
            beta: hit.v.beta,
            edges: hit.v.depth,
            terminated: m.terminated(),
        });
    }

    pub(super) fn append(&mut self, mut other: MapData<C>) {
        self.points.append(&mut other.points);
        self.photons.append(&mut other.photons);
    }

    /// The map; `volume`: a volume map, which keeps its photons' positions.
    pub(super) fn build(self, volume: bool) -> Option<PhotonMap<C>> {
        PhotonMap::new(self.points, self.photons, volume)
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
}
