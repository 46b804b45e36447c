#!/bin/sh
# lumpy_sphere.sh > lumpy.obj: a smooth test model with a coarse tessellation
# and UVs (issue 25's turning test, docs/performance.md): a sphere of radius 1
# centred 1.2 above the origin with lumps of 0.12 and 0.08, 24 x 12 segments
# (528 triangles), equirectangular UVs with a seam, faces wound outwards.
awk 'BEGIN {
    nu = 24; nv = 12; pi = 3.14159265358979
    print "# a lumpy sphere, 24 x 12 segments, equirectangular UVs"
    for (j = 0; j <= nv; j++) {
        ph = pi * j / nv
        for (i = 0; i <= nu; i++) {
            th = 2 * pi * i / nu
            r = 1 + 0.12 * sin(3 * th) * sin(2 * ph) + 0.08 * cos(5 * ph)
            printf "v %.6f %.6f %.6f\n", r * sin(ph) * cos(th), r * cos(ph) + 1.2, r * sin(ph) * sin(th)
        }
    }
    for (j = 0; j <= nv; j++)
        for (i = 0; i <= nu; i++)
            printf "vt %.6f %.6f\n", i / nu, 1 - j / nv
    for (j = 0; j < nv; j++)
        for (i = 0; i < nu; i++) {
            a = j * (nu + 1) + i + 1; b = a + 1; d = a + nu + 1; c = d + 1
            if (j > 0) printf "f %d/%d %d/%d %d/%d\n", a, a, b, b, c, c
            if (j < nv - 1) printf "f %d/%d %d/%d %d/%d\n", a, a, c, c, d, d
        }
}'
