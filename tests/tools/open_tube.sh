#!/bin/sh
# open_tube.sh [ANGLE] > tube.obj: a test model for the turn (issue 25,
# docs/performance.md, "An open tube lined up with the grid"): a horizontal
# tube of radius 0.5 around y = 1, 2.4 long, 32 x 8 segments, its ends open
# (one-sided walls, wound outwards), UVs around (u) and along (v), its axis
# turned ANGLE degrees (default 0) about +Y from +X. --capped closes its ends
# with two fans (a closed solid).
capped=0
[ "${2:-}" = --capped ] && capped=1
awk -v ang="${1:-0}" -v capped="$capped" 'BEGIN {
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
            printf "f %d/%d %d/%d %d/%d\n", a, a, b, b, e, e
            printf "f %d/%d %d/%d %d/%d\n", a, a, e, e, d, d
        }
    if (capped) {
        # The centres of the ends (UVs on the first and last rows), fans
        # wound outwards (-x at the first ring, +x at the last).
        n = (nx + 1) * (nu + 1)
        printf "v %.7f %.7f %.7f\n", -c * L, cy, s * L
        printf "v %.7f %.7f %.7f\n", c * L, cy, -s * L
        printf "vt 0.5 0\nvt 0.5 1\n"
        for (i = 0; i < nu; i++) {
            a = i + 1; b = a + 1
            printf "f %d/%d %d/%d %d/%d\n", n + 1, n + 1, b, b, a, a
            a = nx * (nu + 1) + i + 1; b = a + 1
            printf "f %d/%d %d/%d %d/%d\n", n + 2, n + 2, a, a, b, b
        }
    }
}'
