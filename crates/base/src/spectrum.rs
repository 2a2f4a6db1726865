//! A spectrum as a scene declared it, in the form spectral rendering samples it: data only
//! (the renderer evaluates it, `render::spectral::declared`, which states the units). Here,
//! beside the loaders' vocabulary, so that the renderer's parameters (`render::textures`) can
//! hold one without naming the spectral toolkit.

/// A declared spectrum (values per nm of wavelength where they are radiometric).
#[derive(Clone, Debug, PartialEq)]
pub enum DeclaredSpectrum {
    /// Linear through the nodes (`wavelengths` in nm, strictly increasing, at least two),
    /// zero outside the first and last.
    Tabulated {
        wavelengths: Box<[f32]>,
        values: Box<[f32]>,
        /// Where a lookup starts (a search index, derived from `wavelengths`): cell `k`
        /// covers wavelengths[0] + [k, k + 1)/`cells_per_nm` and holds the interval (its left
        /// node, at most n − 2) that contains the cell's start. A lookup in the middle of a
        /// path walks at most a node or two from there instead of a binary search per
        /// wavelength (a fifth of a spectral render's time with measured conductors).
        cells: Box<[u32]>,
        /// 1 / the cells' width in nm.
        cells_per_nm: f32,
    },
    /// The same value at every wavelength.
    Constant(f32),
    /// `scale` × Planck's law at `temperature` K, in W·m⁻²·sr⁻¹·nm⁻¹.
    Blackbody { temperature: f64, scale: f64 },
}

impl DeclaredSpectrum {
    /// A tabulated spectrum; `None` unless there are at least two nodes, as many values as
    /// wavelengths, all finite, and the wavelengths strictly increase.
    pub fn tabulated(wavelengths: &[f32], values: &[f32]) -> Option<DeclaredSpectrum> {
        let ok = wavelengths.len() >= 2
            && wavelengths.len() == values.len()
            && wavelengths.iter().chain(values).all(|v| v.is_finite())
            && wavelengths.windows(2).all(|w| w[0] < w[1]);
        if !ok {
            return None;
        }
        let n = wavelengths.len();
        let (w0, span) = (wavelengths[0], wavelengths[n - 1] - wavelengths[0]);
        // 1 nm cells, at most MAX_CELLS of them (a declared range of any width costs ≤ 16 KB).
        const MAX_CELLS: f32 = 4096.0;
        let cell_width = (span / MAX_CELLS).max(1.0);
        let count = (span / cell_width) as usize + 1;
        let mut cells = Vec::with_capacity(count);
        let mut i = 0;
        for k in 0..count {
            let start = w0 + k as f32 * cell_width;
            while i + 2 < n && wavelengths[i + 1] <= start {
                i += 1;
            }
            cells.push(i as u32);
        }
        Some(DeclaredSpectrum::Tabulated {
            wavelengths: wavelengths.into(),
            values: values.into(),
            cells: cells.into(),
            cells_per_nm: 1.0 / cell_width,
        })
    }

    /// The interval of a tabulated spectrum that holds `lambda` ∈ [first, last node]: the
    /// last node at or below it, at most n − 2 (what a binary search gives), found from its
    /// cell.
    #[inline]
    pub fn interval(wavelengths: &[f32], cells: &[u32], cells_per_nm: f32, lambda: f32) -> usize {
        let n = wavelengths.len();
        let k = (((lambda - wavelengths[0]) * cells_per_nm) as usize).min(cells.len() - 1);
        let mut i = cells[k] as usize;
        // Rounding may put `lambda` a cell off: walk either way to the exact interval.
        while i > 0 && wavelengths[i] > lambda {
            i -= 1;
        }
        while i + 2 < n && wavelengths[i + 1] <= lambda {
            i += 1;
        }
        i
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cell-started search finds the binary search's interval at every wavelength in
    /// range, for irregular nodes, nodes closer and farther apart than a cell, and a range
    /// wide enough to need wider cells.
    #[test]
    fn interval_is_the_binary_search() {
        let sets: [Vec<f32>; 4] = [
            vec![360.0, 361.5, 361.7, 362.0, 400.25, 401.0, 830.0],
            (0..95).map(|k| 360.0 + 5.0 * k as f32).collect(),
            vec![200.0, 1700.0],
            vec![1.0, 2.0, 5e4, 1e6, 1e6 + 0.5],
        ];
        for w in sets {
            let v: Vec<f32> = w.iter().map(|_| 1.0).collect();
            let Some(DeclaredSpectrum::Tabulated {
                wavelengths,
                cells,
                cells_per_nm,
                ..
            }) = DeclaredSpectrum::tabulated(&w, &v)
            else {
                panic!("{w:?}");
            };
            assert!(cells.len() <= 4097);
            let n = w.len();
            let (lo, hi) = (w[0], w[n - 1]);
            let mut probes: Vec<f32> = (0..=20_000)
                .map(|k| lo + (hi - lo) * k as f32 / 20_000.0)
                .collect();
            probes.extend(w.iter().copied());
            probes.extend(
                w.iter()
                    .map(|&x| f32::from_bits(x.to_bits() - 1))
                    .filter(|&x| x >= lo),
            );
            for l in probes {
                let want = w.partition_point(|&x| x <= l).saturating_sub(1).min(n - 2);
                assert_eq!(
                    DeclaredSpectrum::interval(&wavelengths, &cells, cells_per_nm, l),
                    want,
                    "{l} in {w:?}"
                );
            }
        }
    }
}
