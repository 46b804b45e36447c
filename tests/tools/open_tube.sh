#!/bin/sh
# open_tube.sh [ANGLE] > tube.obj: a test model for the turn (issue 25,
# docs/performance.md, "An open tube lined up with the grid"): a horizontal
# tube of radius 0.5 around y = 1, 2.4 long, 32 x 8 segments, its ends open
# (one-sided walls), UVs around (u) and along (v), its axis turned ANGLE
# degrees (default 0) about +Y from +X.
awk -v ang="${1:-0}" 'BEGIN {
    nu = 32; nx = 8; pi = 3.14159265358979; R = 0.5; L = 1.2; cy = 1.0
    c = cos(ang * pi / 180); s = sin(ang * pi / 180)
    print "# an open tube, 32 x 8 segments, turned " ang " degrees"
    for (j = 0; j <= nx; j++)
        for (i = 0; i <= nu; i++) {
            th = 2 * pi * i / nu; x = -L + 2 * L * j / nx; y = cy + R * cos(th); z = R * sin(th)
            printf "v %.7f %.7f %.7f\n", c * x + s * z, y, -s * x + c * z
        }
    for (j = 0; j <= nx; j++)
        for (i = 0; i <= nu; i++)
            printf "vt %.6f %.6f\n", i / nu, j / nx
    for (j = 0; j < nx; j++)
        for (i = 0; i < nu; i++) {
            a = j * (nu + 1) + i + 1; b = a + 1; d = a + nu + 1; e = d + 1
            printf "f %d/%d %d/%d %d/%d\n", a, a, e, e, b, b
            printf "f %d/%d %d/%d %d/%d\n", a, a, d, d, e, e
        }
}'
