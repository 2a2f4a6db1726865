#!/usr/bin/env python3
"""Writes cie_data.rs (beside this file): the CIE 1931 2° colour-matching functions and the CIE
standard illuminant D65 at 1 nm over 360–830 nm, and the XYZ <-> linear sRGB matrices.

Where the numbers come from (both are published CIE tables, shipped by PyPI packages):
- x̄, ȳ, z̄: colour-science's `MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]` (1 nm,
  360–830; the CIE's own table, DOI 10.25039/CIE.DS.xvudnb9b, as given in CIE 015:2004),
  cross-checked value by value against luxpy's `data/cmfs/ciexyz_1931_2.dat` (CVRL's copy).
- D65: luxpy's `data/spds/CIE_D65.csv` (the CIE's 1 nm D65, 360–830: CIE S 014-2 / ISO 11664-2,
  DOI 10.25039/CIE.DS.hjfjmt59), cross-checked against colour-science's CIE 015:2004 Table T.1
  (5 nm, 300–780): equal at the 5 nm nodes, and equal to their linear interpolation (the rule
  CIE 015:2004 gives for D illuminants) to the 1 nm table's printed digits. colour-science's
  table stops at 780 nm, hence luxpy's for the whole range.
- The sRGB matrices: ITU-R BT.709 / IEC 61966-2-1 primaries, and as white point the
  chromaticity of the D65 table above under the CMFs above (as pbrt-v4 builds its colour
  spaces), so that a flat unit reflectance under D65 maps to RGB (1, 1, 1) exactly.

Run (it makes its own virtual environment under /tmp when colour-science is not importable):
    python3 crates/base/src/gen_cie.py
"""

import os
import subprocess
import sys
import tempfile
import zipfile

COLOUR = "colour-science==0.4.7"
LUXPY = "luxpy==1.12.5"
HERE = os.path.dirname(os.path.abspath(__file__))


def bootstrap():
    """Re-runs this script inside a venv with colour-science, given the luxpy wheel."""
    venv = os.path.join(tempfile.gettempdir(), "penumbra-gen-cie-venv")
    py = os.path.join(venv, "bin", "python")
    if not os.path.exists(py):
        subprocess.check_call([sys.executable, "-m", "venv", venv])
    subprocess.check_call([py, "-m", "pip", "install", "-q", COLOUR])
    wheels = os.path.join(venv, "wheels")
    subprocess.check_call(
        [py, "-m", "pip", "download", "-q", "--no-deps", "-d", wheels, LUXPY]
    )
    os.execv(py, [py, os.path.abspath(__file__)])


def luxpy_wheel():
    venv = os.path.dirname(os.path.dirname(sys.executable))
    wheels = os.path.join(venv, "wheels")
    if not os.path.isdir(wheels):
        bootstrap()
    names = [n for n in os.listdir(wheels) if n.startswith("luxpy-") and n.endswith(".whl")]
    if not names:
        bootstrap()
    return zipfile.ZipFile(os.path.join(wheels, sorted(names)[-1]))


def read_csv(z, name):
    rows = []
    for line in z.read(name).decode().splitlines():
        line = line.strip()
        if line:
            rows.append([float(v) for v in line.split(",")])
    return rows


def fmt_table(name, values, doc):
    lines = [f"/// {doc}", "#[rustfmt::skip]", f"pub static {name}: [f64; N] = ["]
    line = "   "
    for v in values:
        item = f" {float(v)!r},"
        if len(line) + len(item) > 100:
            lines.append(line)
            line = "   "
        line += item
    lines.append(line)
    lines.append("];")
    return "\n".join(lines)


def fmt_matrix(name, m, doc):
    rows = "".join(
        "    [" + ", ".join(f"{float(v)!r}" for v in row) + "],\n" for row in m
    )
    return f"/// {doc}\n#[rustfmt::skip]\npub const {name}: [[f64; 3]; 3] = [\n{rows}];"


def main():
    try:
        import colour  # noqa: F401
        import numpy as np
    except ImportError:
        bootstrap()
    import warnings

    warnings.filterwarnings("ignore")
    import colour
    import numpy as np

    wl = np.arange(360, 831)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    assert list(cmfs.wavelengths) == list(wl), "colour-science CMFs are not 360..830 at 1 nm"
    xyz = cmfs.values

    z = luxpy_wheel()
    lux_cmf = np.array(read_csv(z, "luxpy/data/cmfs/ciexyz_1931_2.dat"))
    assert (lux_cmf[:, 0] == wl).all()
    assert np.abs(lux_cmf[:, 1:] - xyz).max() < 1e-12, "colour-science and luxpy CMFs differ"

    d65_rows = np.array(read_csv(z, "luxpy/data/spds/CIE_D65.csv"))
    assert (d65_rows[:, 0] == wl).all(), "luxpy D65 is not 360..830 at 1 nm"
    d65 = d65_rows[:, 1]
    t1 = colour.SDS_ILLUMINANTS["D65"]  # CIE 015:2004 Table T.1, 300..780 at 5 nm
    nodes = (wl % 5 == 0) & (wl <= 780)
    assert np.abs(d65[nodes] - t1[wl[nodes]]).max() < 1e-9, "D65 differs at the 5 nm nodes"
    inner = wl <= 780
    lin = np.interp(wl[inner], t1.wavelengths, t1.values)
    assert np.abs(lin - d65[inner]).max() < 1e-3, "1 nm D65 is not the 5 nm table interpolated"
    assert d65[wl == 560][0] == 100.0

    # sRGB: BT.709 primaries, the D65 table's white under these CMFs.
    white = (d65[:, None] * xyz).sum(0)
    white = white / white[1]
    prim = np.array([[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]])
    p = np.array([[x / y, 1.0, (1 - x - y) / y] for x, y in prim]).T
    s = np.linalg.solve(p, white)
    rgb_to_xyz = p * s[None, :]
    xyz_to_rgb = np.linalg.inv(rgb_to_xyz)
    assert np.abs(xyz_to_rgb @ white - 1).max() < 1e-12

    out = [
        "//! GENERATED by `gen_cie.py` (beside this file) — do not edit; rerun it instead.",
        "//!",
        "//! CIE 1931 2° colour-matching functions and CIE standard illuminant D65, 1 nm steps over",
        "//! 360–830 nm, and the XYZ ↔ linear sRGB matrices. Sources (published CIE tables, from",
        "//! PyPI packages; the generator cross-checks them against each other):",
        f"//! - x̄, ȳ, z̄: `{COLOUR}`, `MSDS_CMFS[\"CIE 1931 2 Degree Standard Observer\"]` (the",
        "//!   CIE's 1 nm table, DOI 10.25039/CIE.DS.xvudnb9b / CIE 015:2004), equal to",
        f"//!   `{LUXPY}`'s `data/cmfs/ciexyz_1931_2.dat` to 1e-12.",
        f"//! - D65: `{LUXPY}`'s `data/spds/CIE_D65.csv` (the CIE's 1 nm D65, CIE S 014-2 /",
        "//!   ISO 11664-2, DOI 10.25039/CIE.DS.hjfjmt59), equal to CIE 015:2004 Table T.1",
        f"//!   (`{COLOUR}`, 5 nm, 300–780 nm) at its nodes and to its linear interpolation.",
        "//! - Matrices: ITU-R BT.709 / IEC 61966-2-1 primaries with the white point of the D65",
        "//!   table under the CMFs (x, y = "
        f"{white[0] / white.sum():.6f}, {white[1] / white.sum():.6f}), as pbrt-v4 builds its",
        "//!   colour spaces.",
        "//!",
        "//! The CIE data are published under CC BY-SA 4.0 by the CIE.",
        "",
        "/// Number of samples: 360, 361, ..., 830 nm.",
        "pub const N: usize = 471;",
        "",
        fmt_table("CIE_X", list(xyz[:, 0]), "CIE 1931 2° x̄(λ), λ = 360 + i nm."),
        "",
        fmt_table("CIE_Y", list(xyz[:, 1]), "CIE 1931 2° ȳ(λ), λ = 360 + i nm."),
        "",
        fmt_table("CIE_Z", list(xyz[:, 2]), "CIE 1931 2° z̄(λ), λ = 360 + i nm."),
        "",
        fmt_table("CIE_D65", list(d65), "CIE standard illuminant D65, relative (100 at 560 nm), λ = 360 + i nm."),
        "",
        fmt_matrix("XYZ_TO_SRGB", xyz_to_rgb, "CIE XYZ → linear sRGB (rows: R, G, B)."),
        "",
        fmt_matrix("SRGB_TO_XYZ", rgb_to_xyz, "Linear sRGB → CIE XYZ (rows: X, Y, Z)."),
        "",
    ]
    path = os.path.join(HERE, "cie_data.rs")
    with open(path, "w") as f:
        f.write("\n".join(out))
    print(f"wrote {path}; white point XYZ = {white}")


if __name__ == "__main__":
    main()
