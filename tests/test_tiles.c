// test_tiles.c: a scene cut into tiles and merged (docs/tiles.md, issue 29
// item 1): a street of 2 x 2 houses under wind-driven rain, run whole and as
// 2 x 2 tiles with a halo, each tile run on its own and the tiles merged. The
// merged texture and mask must equal the whole run's within the noise between
// two seeds of the whole run (at 1 x 1, 4 x 4 and 16 x 16 texel blocks), no
// particle is counted twice (the tiles' counts add up to the whole run's), no
// texel is written by two tiles, and the Slurm scripts hold the job array and
// its afterok merge.
#define _XOPEN_SOURCE 700
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "block_rms.h"
#include "ensure.h"
#include "run_fixture.h"

// 2 x 2 houses (boxes 4 x 6 x 4 m with a 0.6 m overhanging roof slab) 8 m
// apart, centred on the origin, so the tiles' borders x = 0 and z = 0 run along
// the streets between them; each house's UVs in its own quarter of the texture
// (the cube's atlas of tests/data/texture_cube.obj, shrunk).
static void write_street(const char *dir)
{
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/street.obj", dir);
    FILE *f = fopen(path, "w");
    ENSURE(f != NULL);
    if (f == NULL) {
        return;
    }
    int base = 1, tbase = 1;
    for (int h = 0; h < 4; ++h) {
        double cx = (h % 2) ? 4.0 : -4.0, cz = (h / 2) ? 4.0 : -4.0;
        double u0 = 0.5 * (h % 2), v0 = 0.5 * (h / 2);
        // Two boxes: the body and the roof slab, each with the cube's 6 faces.
        const double boxes[2][6] = { { -2, 0, -2, 2, 6, 2 }, { -2.6, 6, -2.6, 2.6, 6.3, 2.6 } };
        for (int b = 0; b < 2; ++b) {
            const double *lo = boxes[b], *hi = boxes[b] + 3;
            for (int c = 0; c < 8; ++c) {
                fprintf(f, "v %.4f %.4f %.4f\n", cx + ((c & 1) ? hi[0] : lo[0]),
                        (c & 2) ? hi[1] : lo[1], cz + ((c & 4) ? hi[2] : lo[2]));
            }
            // Faces (corner indices, counter-clockwise from outside) and a
            // cell of a 3 x 4 atlas in the house's quarter: body row 0-1, roof 2-3.
            static const int faces[6][4] = { { 2, 6, 7, 3 }, { 0, 1, 5, 4 }, { 1, 3, 7, 5 },
                                             { 0, 4, 6, 2 }, { 4, 5, 7, 6 }, { 0, 2, 3, 1 } };
            for (int k = 0; k < 6; ++k) {
                double cu = u0 + 0.5 * ((k % 3) + 0.05) / 3.0;
                double cv = v0 + 0.5 * ((2 * b + k / 3) + 0.05) / 4.0;
                double du = 0.5 * 0.9 / 3.0, dv = 0.5 * 0.9 / 4.0;
                fprintf(f, "vt %.6f %.6f\nvt %.6f %.6f\nvt %.6f %.6f\nvt %.6f %.6f\n", cu, cv,
                        cu + du, cv, cu + du, cv + dv, cu, cv + dv);
                const int *q = faces[k];
                fprintf(f, "f %d/%d %d/%d %d/%d\nf %d/%d %d/%d %d/%d\n", base + q[0], tbase,
                        base + q[1], tbase + 1, base + q[2], tbase + 2, base + q[0], tbase,
                        base + q[2], tbase + 2, base + q[3], tbase + 3);
                tbase += 4;
            }
            base += 8;
        }
    }
    fclose(f);
}

static void write_scene(const char *dir)
{
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/street.xml", dir);
    FILE *f = fopen(path, "w");
    ENSURE(f != NULL);
    if (f == NULL) {
        return;
    }
    fputs("<Weathering>\n"
          "  <Solver><BoundingBox size=\"40\" centerY=\"10\"/>"
          "<Simulation timeStep=\"0.01\" steps=\"400\" seed=\"1\"/></Solver>\n"
          "  <ForceFields><Gravity acceleration=\"9.8\"/>"
          "<Wind strength=\"2\" dirX=\"1\" dirY=\"0\" dirZ=\"0.5\"/></ForceFields>\n"
          "  <Emitters><BoxEmitter name=\"rain\" minX=\"-11\" minY=\"12\" minZ=\"-10\" maxX=\"9\""
          " maxY=\"12\" maxZ=\"10\" speed=\"5\" spread=\"8\" rate=\"40000\" start=\"0\""
          " end=\"1\" dirt=\"1\" maxCollisions=\"50\"/></Emitters>\n"
          "  <Collider resilience=\"0.3\" friction=\"0.9\"><ProjectedMaps>\n"
          "    <Ortho cameraName=\"top\"><View eye=\"0 20 0\" target=\"0 0 0\" up=\"0 0 -1\""
          " width=\"20\" height=\"20\" resolution=\"320\"/></Ortho>\n"
          "    <Ortho cameraName=\"east\" layers=\"2\"><View eye=\"20 4 0\" target=\"0 4 0\""
          " up=\"0 1 0\" width=\"20\" height=\"8\" resolution=\"320 128\"/></Ortho>\n"
          "    <Ortho cameraName=\"south\" layers=\"2\"><View eye=\"0 4 20\" target=\"0 4 0\""
          " up=\"0 1 0\" width=\"20\" height=\"8\" resolution=\"320 128\"/></Ortho>\n"
          "    <Ortho cameraName=\"out\" out=\"true\"><View eye=\"0 20 0\" target=\"0 0 0\""
          " up=\"0 0 -1\" width=\"20\" height=\"20\" resolution=\"256\"/>"
          "<OutputMap file=\"mask.exr\" width=\"256\" height=\"256\"/></Ortho>\n"
          "  </ProjectedMaps></Collider>\n"
          "  <Geometry><Mesh file=\"street.obj\">"
          "<Surface material=\"*\" absorption=\"0.3\" bounce=\"0.3\" deposit=\"0.5\""
          " erosion=\"0.1\"/>"
          "<TextureMap file=\"street_texture.exr\" resolution=\"256\" padding=\"4\"/>"
          "</Mesh></Geometry>\n"
          "</Weathering>\n",
          f);
    fclose(f);
}

// "KEY": N of a --stats file, or -1.
static long long stats_value(const char *path, const char *key)
{
    char text[16384], quoted[64];
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        return -1;
    }
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = '\0';
    snprintf(quoted, sizeof quoted, "\"%s\":", key);
    const char *at = strstr(text, quoted);
    long long v = -1;
    return at != NULL && sscanf(at + strlen(quoted), "%lld", &v) == 1 ? v : -1;
}

// The text of DIR/NAME (at most cap - 1 bytes; "" when unreadable).
static void read_text(const char *dir, const char *name, char *text, size_t cap)
{
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "r");
    size_t n = f != NULL ? fread(text, 1, cap - 1, f) : 0;
    text[n] = '\0';
    if (f != NULL) {
        fclose(f);
    }
}

// RMS of the differences of k x k block means of a and b (block_rms.h),
// relative to their mean.
static double block_rms(const float *a, const float *b, const float *seen_a, const float *seen_b,
                        int w, int h, int k)
{
    double mean = wx_block_mean(a, b, seen_a, seen_b, w, h, NULL);
    long blocks = 0;
    double rms = wx_block_rms(a, b, seen_a, seen_b, w, h, k, &blocks);
    return blocks > 0 && mean > 0.0 ? rms / mean : INFINITY;
}

// The merged file against the whole run's, and two seeds of the whole run.
static void compare(const char *dir, const char *name, const char *channel, bool has_seen)
{
    char whole[PATH_MAX + 64], other[PATH_MAX + 64], merged[PATH_MAX + 64];
    snprintf(whole, sizeof whole, "%s/whole/%s", dir, name);
    snprintf(other, sizeof other, "%s/seed2/%s", dir, name);
    snprintf(merged, sizeof merged, "%s/tiles/merged/%s", dir, name);
    int w[3], h[3];
    float *a = ensure_read_channel(whole, channel, &w[0], &h[0]);
    float *b = ensure_read_channel(other, channel, &w[1], &h[1]);
    float *m = ensure_read_channel(merged, channel, &w[2], &h[2]);
    float *sa = has_seen ? ensure_read_channel(whole, "seen", &w[0], &h[0]) : NULL;
    float *sb = has_seen ? ensure_read_channel(other, "seen", &w[1], &h[1]) : NULL;
    float *sm = has_seen ? ensure_read_channel(merged, "seen", &w[2], &h[2]) : NULL;
    bool ok = a != NULL && b != NULL && m != NULL && w[0] == w[1] && w[0] == w[2] && h[0] == h[1] &&
              h[0] == h[2] && (!has_seen || (sa && sb && sm));
    ENSURE(ok);
    if (ok && has_seen) {
        // No texel written by two tiles: seen is 0 or 1, and as the whole run's.
        long differ = 0, twice = 0;
        for (size_t i = 0; i < (size_t)w[0] * (size_t)h[0]; ++i) {
            twice += sm[i] != 0.0f && sm[i] != 1.0f;
            differ += sm[i] != sa[i];
        }
        ENSURE(twice == 0);
        ENSURE(differ * 100 <= (long)w[0] * h[0]);
    }
    for (int k = 1; ok && k <= 16; k *= 4) {
        double tiles = block_rms(a, m, sa, sm, w[0], h[0], k);
        double seeds = block_rms(a, b, sa, sb, w[0], h[0], k);
        printf("        %s %dx%d blocks: merged vs whole %.4f, seed vs seed %.4f\n", name, k, k,
               tiles, seeds);
        ENSURE(tiles <= seeds);
    }
    free(a);
    free(b);
    free(m);
    free(sa);
    free(sb);
    free(sm);
}

TEST(a_street_run_as_tiles_merges_into_the_whole_run)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    write_street(dir);
    write_scene(dir);
    ENSURE(run_in(dir, "run street.xml --out whole --stats whole.json -q%s%s", "", "") == 0);
    ENSURE(run_in(dir, "run street.xml --out seed2 --seed 2 -q%s%s", "", "") == 0);
    ENSURE(run_in(dir, "tiles street.xml --tiles 2 2 --halo 4 --out tiles --slurm%s%s", "", "") ==
           0);
    long long particles = 0;
    for (int t = 0; t < 4; ++t) {
        char name[32];
        snprintf(name, sizeof name, "tile_%d_%d", t % 2, t / 2);
        char args[256];
        snprintf(args, sizeof args, "run tiles/%s.xml --out tiles/%s --stats tiles/%s.json -q",
                 name, name, name);
        ENSURE(weathering_in(dir, args, true) == 0);
        char path[PATH_MAX + 64];
        snprintf(path, sizeof path, "%s/tiles/%s.json", dir, name);
        long long p = stats_value(path, "tile_particles");
        ENSURE(p > 0);
        particles += p;
        snprintf(path, sizeof path, "%s/tiles/%s.xml", dir, name);
        ENSURE(schema_accepts(path));
    }
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/whole.json", dir);
    ENSURE(particles == stats_value(path, "particles_emitted"));
    ENSURE(particles == 40000);
    ENSURE(run_in(dir, "merge tiles%s%s", "", "") == 0);
    ENSURE(strstr(out, "4 tiles") != NULL && strstr(out, "40000 particles") != NULL);
    compare(dir, "street_texture.exr", "Y", true);
    compare(dir, "mask.exr", "Y", false);
    snprintf(path, sizeof path, "%s/tiles/merged/street_texture.png", dir);
    ENSURE(access(path, R_OK) == 0);
    // The Slurm scripts: a job array of the 4 tiles and a merge after it.
    char text[4096];
    read_text(dir, "tiles/tiles.sbatch", text, sizeof text);
    ENSURE(strstr(text, "#SBATCH --array=0-3") != NULL);
    ENSURE(strstr(text, "SLURM_ARRAY_TASK_ID") != NULL);
    read_text(dir, "tiles/submit.sh", text, sizeof text);
    ENSURE(strstr(text, "--dependency=afterok:") != NULL);
}

// A shot's tiles (docs/scale-out.md): of 4 x 4 tiles of the street's 40 m
// box, the output camera (20 m over the centre) sees the middle 2 x 2, tasks
// 5, 6, 9 and 10; tiles names them, and submit.sh takes them as its array.
TEST(tiles_name_the_tasks_the_output_camera_sees)
{
    const char *dir = ensure_tmpdir();
    write_street(dir);
    write_scene(dir);
    ENSURE(run_in(dir, "tiles street.xml --tiles 4 4 --halo 2 --out shot%s%s", " --slurm", "") ==
           0);
    ENSURE(strstr(out, "sees 4 of the 16 tiles (tasks 5,6,9,10") != NULL);
    char path[PATH_MAX + 64], text[4096];
    read_text(dir, "shot/submit.sh", text, sizeof text);
    ENSURE(strstr(text, "the output camera sees tasks: 5,6,9,10.") != NULL);
    ENSURE(strstr(text, "${1:+--array=\"$1\"}") != NULL);
    // Just those tiles, the others' scenes moved away: merge joins them.
    if (!ensure_fast()) {
        char sh[64];
        ENSURE(ensure_shell(sh, sizeof sh,
                            "cd '%s/shot' && mkdir skipped && for t in tile_*.xml; do case $t in "
                            "tile_[12]_[12].xml) ;; *) mv $t skipped/;; esac; done",
                            dir) == 0);
        const char *tiles[] = { "1_1", "2_1", "1_2", "2_2" };
        for (int k = 0; k < 4; ++k) {
            char args[128];
            snprintf(args, sizeof args, "run shot/tile_%s.xml --out shot/tile_%s -q", tiles[k],
                     tiles[k]);
            ENSURE(weathering_in(dir, args, true) == 0);
        }
        ENSURE(run_in(dir, "merge shot%s%s", "", "") == 0);
        ENSURE(strstr(out, "4 tiles") != NULL);
        snprintf(path, sizeof path, "%s/shot/merged/mask.exr", dir);
        ENSURE(access(path, R_OK) == 0);
    }
    // Every tile is seen when the camera covers them all: nothing printed.
    ENSURE(run_in(dir, "tiles street.xml --tiles 2 2 --out all%s%s", "", "") == 0);
    ENSURE(strstr(out, "sees") == NULL);
}

TEST(tiles_and_merge_refuse_what_they_cannot_do)
{
    const char *dir = ensure_tmpdir();
    write_street(dir);
    write_scene(dir);
    ENSURE(run_in(dir, "tiles street.xml%s%s", "", "") == 2);
    ENSURE(run_in(dir, "tiles street.xml --tiles 0 2%s%s", "", "") == 2);
    ENSURE(run_in(dir, "tiles street.xml --tiles 2 2 --halo -1%s%s", "", "") == 2);
    ENSURE(run_in(dir, "run street.xml --halo 3%s%s", "", "") == 2);
    ENSURE(run_in(dir, "merge .%s%s", "", "") == 2);
    ENSURE(strstr(out, "no tile scenes") != NULL);
    // A tile cannot be cut again; a merge before the tiles ran names the folder.
    ENSURE(run_in(dir, "tiles street.xml --tiles 2 1 --out t%s%s", "", "") == 0);
    ENSURE(run_in(dir, "tiles t/tile_0_0.xml --tiles 2 1 --out u%s%s", "", "") == 2);
    ENSURE(strstr(out, "already a tile") != NULL);
    ENSURE(run_in(dir, "merge t%s%s", "", "") == 2);
    ENSURE(strstr(out, "run the tile first") != NULL);
    // Never over the scene it cuts, nor into a tile's own folder.
    char cmd[PATH_MAX + 64];
    snprintf(cmd, sizeof cmd, "cp '%s/street.xml' '%s/tile_0_0.xml'", dir, dir);
    ENSURE(system(cmd) == 0);
    ENSURE(run_in(dir, "tiles tile_0_0.xml --tiles 1 1 --out .%s%s", "", "") == 2);
    ENSURE(strstr(out, "would replace the scene itself") != NULL);
    snprintf(cmd, sizeof cmd, "mkdir -p '%s/t/tile_0_0' '%s/t/tile_1_0'", dir, dir);
    ENSURE(system(cmd) == 0);
    ENSURE(run_in(dir, "merge t --out t/tile_1_0%s%s", "", "") == 2);
    ENSURE(strstr(out, "write over tile 1 0") != NULL);
}

int main(void)
{
    RUN(a_street_run_as_tiles_merges_into_the_whole_run);
    RUN(tiles_and_merge_refuse_what_they_cannot_do);
    RUN(tiles_name_the_tasks_the_output_camera_sees);
    return ensure_summary();
}
