#!/usr/bin/env python3
"""Writes crates/lenspath/data/glass/catalogue.tsv, the optical glasses the
library embeds, from the refractiveindex.info files in ../shared/glass/
(CC0 1.0): per glass its maker, name, dispersion formula and coefficients,
valid wavelength range, n_d, V_d, glass code, and the extinction coefficient
k against wavelength where the file tabulates it (refractiveindex.info's
conversion of the maker's internal transmittance). Run from the repository:
`python3 scripts/glass_catalogue.py [SHARED_GLASS_DIR]`."""

import pathlib
import re
import sys

MAKERS = ["schott", "ohara", "hoya", "cdgm", "sumita", "hikari"]
root = pathlib.Path(__file__).resolve().parent.parent
source = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else root.parent / "shared" / "glass"
out = root / "crates" / "lenspath" / "data" / "glass" / "catalogue.tsv"

formula = re.compile(r"- type: formula (\d)\n\s+wavelength_range: (\S+) (\S+)\n\s+coefficients: (.*)")
extinction = re.compile(r"- type: tabulated k\n\s+data: \|\n((?:[ \t]+\S+[ \t]+\S+\n)+)")
lines = [
    "# Optical glasses of six makers, from the refractiveindex.info database",
    "# (database/data/specs/<maker>/optical/*.yml), released under CC0 1.0",
    "# (public domain; see LICENSE). Written by scripts/glass_catalogue.py.",
    "# Formula 2: n^2 - 1 = c0 + sum B_i l^2 / (l^2 - C_i); formula 3:",
    "# n^2 = c0 + sum a_i l^e_i; wavelengths l in micrometres. k: the",
    "# extinction coefficient as l:k pairs (- where not given).",
    "# maker\tname\tformula\tmin_um\tmax_um\tnd\tVd\tglass_code\tcoefficients\tk",
]
for maker in MAKERS:
    for path in sorted((source / maker / "optical").glob("*.yml")):
        text = path.read_text()
        m = formula.search(text)
        if not m:
            sys.exit(f"{path}: no dispersion formula")
        nd = re.search(r"\n\s+nd: (\S+)", text).group(1)
        vd = re.search(r"\n\s+Vd: (\S+)", text).group(1)
        code = re.search(r"\n\s+glass_code: (\S+)", text)
        k = extinction.search(text)
        k_pairs = "-"
        if k:
            values = k.group(1).split()
            k_pairs = " ".join(f"{w}:{v}" for w, v in zip(values[0::2], values[1::2], strict=True))
        lines.append(
            "\t".join(
                [
                    maker,
                    path.stem,
                    m.group(1),
                    m.group(2),
                    m.group(3),
                    nd,
                    vd,
                    code.group(1) if code else "-",
                    " ".join(m.group(4).split()),
                    k_pairs,
                ]
            )
        )
out.write_text("\n".join(lines) + "\n")
print(f"{len(lines) - 7} glasses -> {out.relative_to(root)}")
