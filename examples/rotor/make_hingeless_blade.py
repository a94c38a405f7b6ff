"""Writes nrel5mw_blade_sections.csv (the `sections_file` of hingeless_blade_campbell.toml)
from the BeamDyn blade file of the NREL 5-MW reference blade.

SOURCE: NREL/ROSCO @ fc11f43984876559c8b355e5070dd8147c4225da,
Examples/Test_Cases/NREL-5MW/NRELOffshrBsline5MW_BeamDyn_Blade.dat (copied unchanged to
reference/nrel5mw/structure/; 49 stations of 6x6 stiffness and mass).

BeamDyn orders the section (shear x, shear y, axial | bending x, bending y, torsion) with
the beam along z; samara (axial, shear y, shear z | torsion, bending y, bending z) with the
beam along x: samara index i takes BeamDyn index PERM[i] (1-based 3, 1, 2, 6, 4, 5), so
BeamDyn's x (the flapwise direction: K55 is the ElastoDyn FlpStff) is samara's local y.

    python3 make_hingeless_blade.py [BEAMDYN_BLADE_FILE]
"""

import os
import sys

PERM = [2, 0, 1, 5, 3, 4]
HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT = os.path.join(HERE, "..", "..", "reference", "nrel5mw",
                       "structure", "NRELOffshrBsline5MW_BeamDyn_Blade.dat")


def stations(path):
    lines = open(path).read().splitlines()
    start = next(i for i, l in enumerate(lines) if "DISTRIBUTED PROPERTIES" in l) + 1
    nums = []
    for l in lines[start:]:
        nums.extend(float(x) for x in l.split())
    out = []
    while len(nums) >= 73:
        eta, block = nums[0], nums[1:73]
        nums = nums[73:]
        k = [block[6 * r:6 * r + 6] for r in range(6)]
        m = [block[36 + 6 * r:36 + 6 * r + 6] for r in range(6)]
        out.append((eta, k, m))
    return out


def permute(a):
    return [[a[PERM[i]][PERM[j]] for j in range(6)] for i in range(6)]


def main():
    src = sys.argv[1] if len(sys.argv) > 1 else DEFAULT
    rows = stations(src)
    assert len(rows) == 49, len(rows)
    head = ["station"] + [f"K{i}{j}" for i in range(1, 7) for j in range(1, 7)] \
        + [f"M{i}{j}" for i in range(1, 7) for j in range(1, 7)]
    with open(os.path.join(HERE, "nrel5mw_blade_sections.csv"), "w") as f:
        f.write(",".join(head) + "\n")
        for eta, k, m in rows:
            vals = [eta] + [x for r in permute(k) for x in r] + [x for r in permute(m) for x in r]
            f.write(",".join(repr(v) for v in vals) + "\n")


if __name__ == "__main__":
    main()
