#!/bin/sh
# trough.sh [TILT] > trough.obj: a test model with sharp edges (issue 25's
# turning test, docs/performance.md, "Edges"): a closed block 3 x 2 x 1.5 m
# whose top holds a smooth valley along x (0.35 m deep, 1.4 m wide, a cos^2
# profile) between two flat strips, the whole top tilted TILT (default 0.2) in
# y per metre of x so that water runs along the valley; 12 x 16 segments on
# the top, faces wound outwards, UVs: the top over v 0.3..1, the bottom, the
# long sides and the ends in thin strips below.
awk -v tilt="${1:-0.2}" 'function top(x, z,   p) {
        p = 0.5
        if (z < 0.7 && z > -0.7) p = 0.5 - 0.35 * cos(3.14159265358979 * z / 1.4) ^ 2
        return p - tilt * x
    }
    function v(x, y, z) { nv++; printf "v %.6f %.6f %.6f\n", x, y, z; return nv }
    function t(a, b) { nt++; printf "vt %.6f %.6f\n", a, b; return nt }
    function quad(a, ta, b, tb, c, tc, d, td) {
        faces[++nf] = sprintf("f %d/%d %d/%d %d/%d", a, ta, b, tb, c, tc)
        faces[++nf] = sprintf("f %d/%d %d/%d %d/%d", a, ta, c, tc, d, td)
    }
    BEGIN {
        NX = 12; NZ = 16; X0 = -1.5; X1 = 1.5; Z0 = -1; Z1 = 1; YB = -1
        print "# a tilted trough with a smooth valley, 12 x 16 segments on its top"
        for (i = 0; i <= NX; i++) for (j = 0; j <= NZ; j++) {
            x = X0 + (X1 - X0) * i / NX; z = Z0 + (Z1 - Z0) * j / NZ
            gv[i, j] = v(x, top(x, z), z); gt[i, j] = t(i / NX, 0.3 + 0.7 * j / NZ)
        }
        for (i = 0; i < NX; i++) for (j = 0; j < NZ; j++)
            quad(gv[i, j], gt[i, j], gv[i, j + 1], gt[i, j + 1], gv[i + 1, j + 1], gt[i + 1, j + 1],
                 gv[i + 1, j], gt[i + 1, j])
        for (i = 0; i <= NX; i++) for (j = 0; j <= NZ; j += NZ) {
            x = X0 + (X1 - X0) * i / NX; z = Z0 + (Z1 - Z0) * j / NZ
            bv[i, j] = v(x, YB, z); bt[i, j] = t(i / NX, 0.1 * j / NZ)
        }
        for (i = 0; i < NX; i++)
            quad(bv[i, 0], bt[i, 0], bv[i + 1, 0], bt[i + 1, 0], bv[i + 1, NZ], bt[i + 1, NZ],
                 bv[i, NZ], bt[i, NZ])
        # the long sides, z = -1 (v 0.1..0.19) and z = 1 (v 0.2..0.29)
        for (s = 0; s < 2; s++) {
            j = s * NZ; v0 = 0.1 + 0.1 * s
            for (i = 0; i <= NX; i++) {
                x = X0 + (X1 - X0) * i / NX; z = Z0 + (Z1 - Z0) * j / NZ
                lv[i] = v(x, YB, z); lt[i] = t(i / NX, v0); hv[i] = v(x, top(x, z), z); ht[i] = t(i / NX, v0 + 0.09)
            }
            for (i = 0; i < NX; i++)
                if (s == 1) quad(lv[i], lt[i], lv[i + 1], lt[i + 1], hv[i + 1], ht[i + 1], hv[i], ht[i])
                else quad(lv[i], lt[i], hv[i], ht[i], hv[i + 1], ht[i + 1], lv[i + 1], lt[i + 1])
        }
        # the ends, x = -1.5 (u 0..0.49) and x = 1.5 (u 0.5..0.99), v 0.291..0.299
        for (s = 0; s < 2; s++) {
            i = s * NX; u0 = 0.5 * s
            for (j = 0; j <= NZ; j++) {
                x = X0 + (X1 - X0) * i / NX; z = Z0 + (Z1 - Z0) * j / NZ
                lv[j] = v(x, YB, z); lt[j] = t(u0 + 0.49 * j / NZ, 0.291)
                hv[j] = v(x, top(x, z), z); ht[j] = t(u0 + 0.49 * j / NZ, 0.299)
            }
            for (j = 0; j < NZ; j++)
                if (s == 1) quad(lv[j], lt[j], hv[j], ht[j], hv[j + 1], ht[j + 1], lv[j + 1], lt[j + 1])
                else quad(lv[j], lt[j], lv[j + 1], lt[j + 1], hv[j + 1], ht[j + 1], hv[j], ht[j])
        }
        for (k = 1; k <= nf; k++) print faces[k]
    }'
