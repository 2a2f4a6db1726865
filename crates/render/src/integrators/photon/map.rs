//! Photon maps: photons in a k-d tree (the `kiddo` crate, built from the photons in
//! emission order) and the radiance estimates read from them.

use std::num::NonZero;

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use super::{Kernel, Lookup};
use crate::bsdf::TransportMode;
use crate::integrators::photons::PhotonHit;
use crate::integrators::transport::Scatterer;
use crate::math::{PI, Vec3};
use crate::media::Phase;
use crate::spectral::lanes::{Color, PathMode};

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
    /// Up to 1024 photon positions spread evenly over the emission order
    /// ([`PhotonMap::resolve`]).
    sample: Vec<[f32; 3]>,
}

impl<C: Color> PhotonMap<C> {
    fn new(points: Vec<[f32; 3]>, photons: Vec<StoredPhoton<C>>) -> Option<PhotonMap<C>> {
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

    /// Σ `term`(photon, d², r²) over the photons `lookup` finds around `p` whose path fits
    /// in `budget` edges, r the radius of the region searched: [photons whose wavelengths
    /// are all live, photons that terminated their secondaries] (spectral mode; see
    /// [`Estimate`]).
    fn sum(
        &self,
        lookup: Lookup,
        p: Vec3,
        budget: Option<u32>,
        term: impl Fn(&StoredPhoton<C>, f32, f32) -> C,
    ) -> Estimate<C> {
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
                        .execute()
                } else {
                    self.tree
                        .query(&q)
                        .nearest_n::<SquaredEuclidean<f32>>(k)
                        .execute()
                };
                // The radius of the region the photons were found in: the k-th distance, or
                // the cap when fewer were found within it.
                let r2 = if found.len() == k.get() || !max_radius.is_finite() {
                    found.last().map_or(0.0, |n| n.distance)
                } else {
                    max_radius * max_radius
                };
                (found, r2)
            }
        };
        let mut sum = Estimate([C::ZERO; 2]);
        if r2.is_nan() || r2 <= 0.0 {
            return sum;
        }
        for n in &found {
            let ph = &self.photons[n.item as usize];
            if budget.is_some_and(|b| ph.edges > b) {
                continue;
            }
            sum.0[ph.terminated as usize] += term(ph, n.distance, r2);
        }
        sum
    }

    /// Σ K·β and Σ (K·β)² over the photons `lookup` finds around `p`: N times the
    /// irradiance estimate there (of photons of every depth) and what its variance is
    /// estimated from (tests of the density estimation).
    pub fn irradiance_sums(&self, lookup: Lookup, kernel: Kernel, p: Vec3) -> (C, C) {
        let sq = std::cell::Cell::new(C::ZERO);
        let Estimate([live, terminated]) = self.sum(lookup, p, None, |ph, d2, r2| {
            let c = ph.beta * kernel_weight(kernel, d2, r2);
            sq.set(sq.get() + c * c);
            c
        });
        (live + terminated, sq.get())
    }

    /// The estimate at a vertex scattering by `at`, not yet divided by the number of
    /// photons emitted: at a surface Σ K·f·β over the photons around `p` (f without its
    /// cosine: the photon's power holds it); in a medium Σ p(wo, wᵢ)·β / (4/3·π·r³) over the
    /// photons scattered around `p`, σs times the in-scattered radiance (the kernel does not
    /// apply there).
    pub(super) fn estimate(
        &self,
        lookup: Lookup,
        kernel: Kernel,
        p: Vec3,
        at: &Scatterer<C>,
        budget: Option<u32>,
    ) -> Estimate<C> {
        match *at {
            Scatterer::Surface { bsdf, frame, wo } => self.sum(lookup, p, budget, |ph, d2, r2| {
                let wl = frame.to_local(ph.wi);
                if wl.z == 0.0 {
                    return C::ZERO;
                }
                let f = bsdf.eval(wo, wl, TransportMode::Radiance) / wl.z.abs();
                f * ph.beta * kernel_weight(kernel, d2, r2)
            }),
            Scatterer::Medium { phase, wo } => volume_sum(self, lookup, p, phase, wo, budget),
        }
    }
}

/// [`PhotonMap::estimate`] in a medium.
fn volume_sum<C: Color>(
    map: &PhotonMap<C>,
    lookup: Lookup,
    p: Vec3,
    phase: &Phase,
    wo: Vec3,
    budget: Option<u32>,
) -> Estimate<C> {
    map.sum(lookup, p, budget, |ph, _, r2| {
        let v = 4.0 / 3.0 * PI * r2 * r2.sqrt();
        ph.beta * (phase.eval(wo, ph.wi) / v)
    })
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

    pub(super) fn build(self) -> Option<PhotonMap<C>> {
        PhotonMap::new(self.points, self.photons)
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
        let map = PhotonMap::new(points, photons).unwrap();
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
