// gen_building.c: writes the default scene's building as an OBJ made of boxes,
// with a .mtl naming its materials: a four-storey house with recessed windows,
// sills under them, a balcony, a cornice under an overhanging roof, and the
// ground around it. Y is up; the facade faces +Z.
//
// UV layout (for <TextureMap>): every face of every box is its own island, its
// four corners their own vertices with their own `vt`. A face is unfolded flat
// and unstretched, at one texel density shared by all faces (metres per UV unit
// equal in u and v): on a vertical face +v is world up (+Y), on the others
// (|normal.y| >= 0.5) +u is world +X; u x v is the outward normal, so the
// triangles stay counter-clockwise in UV too. The islands' bounding rectangles
// are packed by a shelf packer (tallest first) into [0,1]^2 with a gutter of
// GUTTER_TEXELS texels of a TEXTURE_SIZE texture between islands and to the
// border, at the largest density that fits (a bisection). An island narrower
// than MIN_TEXELS texels in u or v is widened to that (only there is the
// texture stretched): the 1 mm sides of the glass, the 4 cm rails. The sides of
// the sloped sills are parallelograms, so their islands are too, inside their
// rectangle. Coverage and density are printed (stderr) and written at the top
// of the OBJ.
//
//   cc -o gen_building tests/tools/gen_building.c && ./gen_building xml_scenes/meshes
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TEXTURE_SIZE  2048 // the texture the gutter and the minimum size are counted in
#define GUTTER_TEXELS 6.0  // between islands and to the border of the tile
#define MIN_TEXELS    2.0  // smallest side of an island
#define MAX_BOXES     256
#define MAX_FACES     (6 * MAX_BOXES)

// One box face: its corners (in the winding order of its two triangles), its
// unfolded shape in metres and, once packed, where its island lies.
typedef struct face {
    double corner[4][3];
    double flat[4][2];    // the corners in the face's (u, v) frame, metres, min at 0
    double width, height; // extent of `flat`, metres
    double size[2];       // the island's extent in UV at the current density
    double origin[2];     // the island's lower left corner in UV
} face;

typedef struct box_record {
    const char *material;
    int first_face;
} box_record;

static face faces[MAX_FACES];
static box_record boxes[MAX_BOXES];
static int face_count, box_count;

static double root(double x) // sqrt without libm, for the command line above
{
    if (x <= 0.0) {
        return 0.0;
    }
    double r = x > 1.0 ? x : 1.0;
    for (int i = 0; i < 200; ++i) {
        double next = 0.5 * (r + x / r);
        if (next >= r) {
            break;
        }
        r = next;
    }
    return r;
}

static void normalize(double v[3])
{
    double len = root(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; ++k) {
        v[k] /= len;
    }
}

static void cross(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// Unfolds a planar quad: the outward normal n (Newell's), then a frame (u, v)
// in its plane with u x v = n: on a vertical face v is world up, on the others
// u is world +X.
static void unfold(face *f)
{
    double n[3] = { 0, 0, 0 };
    for (int k = 0; k < 4; ++k) {
        const double *a = f->corner[k], *b = f->corner[(k + 1) % 4];
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    normalize(n);
    double u[3], v[3];
    if (n[1] > -0.5 && n[1] < 0.5) {
        double up[3] = { 0, 1, 0 };
        for (int k = 0; k < 3; ++k) {
            v[k] = up[k] - n[1] * n[k];
        }
        normalize(v);
        cross(v, n, u);
    } else {
        double east[3] = { 1, 0, 0 };
        for (int k = 0; k < 3; ++k) {
            u[k] = east[k] - n[0] * n[k];
        }
        normalize(u);
        cross(n, u, v);
    }
    double lo[2] = { 1e300, 1e300 }, hi[2] = { -1e300, -1e300 };
    for (int k = 0; k < 4; ++k) {
        f->flat[k][0] = dot(f->corner[k], u);
        f->flat[k][1] = dot(f->corner[k], v);
        for (int a = 0; a < 2; ++a) {
            lo[a] = f->flat[k][a] < lo[a] ? f->flat[k][a] : lo[a];
            hi[a] = f->flat[k][a] > hi[a] ? f->flat[k][a] : hi[a];
        }
    }
    for (int k = 0; k < 4; ++k) {
        f->flat[k][0] -= lo[0];
        f->flat[k][1] -= lo[1];
    }
    f->width = hi[0] - lo[0];
    f->height = hi[1] - lo[1];
}

// A hexahedron from its 8 corners, corner k being the (x bit 0, y bit 1, z bit 2)
// corner of the box it deforms; faces wound counter-clockwise seen from outside.
static void hexahedron(const char *material, double corner[8][3])
{
    static const int quads[6][4] = {
        { 0, 4, 6, 2 }, // -X
        { 1, 3, 7, 5 }, // +X
        { 0, 1, 5, 4 }, // -Y
        { 2, 6, 7, 3 }, // +Y
        { 0, 2, 3, 1 }, // -Z
        { 4, 5, 7, 6 }, // +Z
    };
    if (box_count == MAX_BOXES) {
        fprintf(stderr, "gen_building: more than %d boxes\n", MAX_BOXES);
        exit(1);
    }
    boxes[box_count].material = material;
    boxes[box_count].first_face = face_count;
    box_count += 1;
    for (int q = 0; q < 6; ++q) {
        face *f = &faces[face_count++];
        for (int k = 0; k < 4; ++k) {
            memcpy(f->corner[k], corner[quads[q][k]], sizeof f->corner[k]);
        }
        unfold(f);
    }
}

// A box from (x0,y0,z0) to (x1,y1,z1) whose +Z (front) edges are lowered by
// `drop`: 0 gives an axis-aligned box, more a top sloping down towards +Z.
static void sloped_box(const char *material, double x0, double y0, double z0, double x1, double y1,
                       double z1, double drop)
{
    double corner[8][3];
    for (int k = 0; k < 8; ++k) {
        corner[k][0] = (k & 1) ? x1 : x0;
        corner[k][1] = ((k >> 1) & 1 ? y1 : y0) - ((k >> 2) & 1 ? drop : 0.0);
        corner[k][2] = (k >> 2) & 1 ? z1 : z0;
    }
    hexahedron(material, corner);
}

static void box(const char *material, double x0, double y0, double z0, double x1, double y1,
                double z1)
{
    sloped_box(material, x0, y0, z0, x1, y1, z1, 0.0);
}

static int order[MAX_FACES];

static int taller_first(const void *pa, const void *pb)
{
    const face *a = &faces[*(const int *)pa], *b = &faces[*(const int *)pb];
    if (a->size[1] != b->size[1]) {
        return a->size[1] < b->size[1] ? 1 : -1;
    }
    if (a->size[0] != b->size[0]) {
        return a->size[0] < b->size[0] ? 1 : -1;
    }
    return *(const int *)pa - *(const int *)pb;
}

// Shelf packing at `density` UV units per metre: islands sorted tallest first,
// laid left to right in rows from the top of the tile (v = 1) down. Returns
// whether they all fit; the islands' origins are set either way.
static int pack(double density)
{
    const double gutter = GUTTER_TEXELS / TEXTURE_SIZE, least = MIN_TEXELS / TEXTURE_SIZE;
    for (int i = 0; i < face_count; ++i) {
        faces[i].size[0] = faces[i].width * density > least ? faces[i].width * density : least;
        faces[i].size[1] = faces[i].height * density > least ? faces[i].height * density : least;
        order[i] = i;
    }
    qsort(order, (size_t)face_count, sizeof order[0], taller_first);
    double x = gutter, top = gutter, shelf = 0.0; // top: distance of the shelf from v = 1
    for (int i = 0; i < face_count; ++i) {
        face *f = &faces[order[i]];
        if (f->size[0] > 1.0 - 2.0 * gutter) {
            return 0;
        }
        if (x + f->size[0] > 1.0 - gutter) {
            top += shelf + gutter;
            x = gutter;
            shelf = 0.0;
        }
        if (shelf == 0.0) {
            shelf = f->size[1];
        }
        f->origin[0] = x;
        f->origin[1] = 1.0 - top - f->size[1];
        x += f->size[0] + gutter;
    }
    return top + shelf <= 1.0 - gutter;
}

// The corner's texture coordinates: its unfolded position at the island's
// scale, widened where the island was clamped.
static void corner_uv(const face *f, int k, double density, double uv[2])
{
    double scale[2] = { density, density };
    if (f->width * density < f->size[0]) {
        scale[0] = f->size[0] / f->width;
    }
    if (f->height * density < f->size[1]) {
        scale[1] = f->size[1] / f->height;
    }
    for (int a = 0; a < 2; ++a) {
        uv[a] = f->origin[a] + f->flat[k][a] * scale[a];
    }
}

static double island_area(const face *f, double density)
{
    double uv[4][2], area = 0.0;
    for (int k = 0; k < 4; ++k) {
        corner_uv(f, k, density, uv[k]);
    }
    for (int k = 0; k < 4; ++k) {
        area += uv[k][0] * uv[(k + 1) % 4][1] - uv[(k + 1) % 4][0] * uv[k][1];
    }
    return 0.5 * area;
}

static void build(void)
{
    // Dimensions (metres). Body 10 x 12 x 6, facade plane at z = 3.
    const double half_w = 5.0, height = 12.0, back = -3.0, front = 3.0, recess = 0.2;
    const int floors = 4, columns = 3;
    const double floor_h = height / floors;
    const double win_w = 1.4, win_h = 1.6, sill_y = 0.9; // window above floor level
    const double sill_out = 0.12, sill_drop = 0.16;      // sill overhang, slope

    box("ground", -7, -0.2, -7, 7, 0.0, 7);
    // Core of the building, its front face is the glass behind the openings.
    box("wall", -half_w, 0, back, half_w, height, front - recess);
    box("glass", -half_w + 0.01, 0.01, front - recess, half_w - 0.01, height - 0.01,
        front - recess + 0.001);

    // Facade layer with window openings: columns of piers and, per floor, the
    // wall below and above each window.
    double span = 2.0 * half_w / columns;
    for (int c = 0; c < columns; ++c) {
        double cx = -half_w + span * (c + 0.5);
        double wx0 = cx - win_w / 2, wx1 = cx + win_w / 2;
        double left = -half_w + span * c, right = left + span;
        box("wall", left, 0, front - recess, wx0, height, front);
        box("wall", wx1, 0, front - recess, right, height, front);
        for (int f = 0; f < floors; ++f) {
            double y0 = f * floor_h;
            double wy0 = y0 + sill_y, wy1 = wy0 + win_h;
            // The wall under the window stops below the sill, whose top slopes
            // down towards the street: it must not poke through it.
            box("wall", wx0, y0, front - recess, wx1, wy0 - 0.08 - sill_drop, front);
            box("wall", wx0, wy1, front - recess, wx1, y0 + floor_h, front);
            // Sill: a slab under the opening, sticking out of the facade, its top
            // sloping outwards so that rain runs off its front edge.
            sloped_box("sill", wx0 - 0.1, wy0 - 0.08, front - recess, wx1 + 0.1, wy0,
                       front + sill_out, sill_drop);
        }
    }
    // Balcony on the second floor, centre bay: slab, railing posts and top rail.
    const double by = floor_h, bz1 = front + 1.2, bx0 = -1.6, bx1 = 1.6;
    box("wall", bx0, by - 0.15, front, bx1, by, bz1);
    for (int p = 0; p <= 8; ++p) {
        double x = bx0 + 0.05 + (bx1 - bx0 - 0.1) * p / 8.0;
        box("metal", x - 0.02, by, bz1 - 0.06, x + 0.02, by + 1.0, bz1 - 0.02);
    }
    box("metal", bx0, by + 1.0, bz1 - 0.08, bx1, by + 1.05, bz1);
    // Cornice and an overhanging roof slab.
    box("sill", -half_w - 0.25, height - 0.3, back - 0.25, half_w + 0.25, height, front + 0.25);
    box("roof", -half_w - 0.7, height, back - 0.7, half_w + 0.7, height + 0.25, front + 0.7);
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : ".";
    char path[4096];
    snprintf(path, sizeof path, "%s/building.mtl", dir);
    FILE *mtl = fopen(path, "w");
    if (mtl == NULL) {
        perror(path);
        return 1;
    }
    const char *materials[][2] = {
        { "wall", "0.80 0.76 0.68" }, { "glass", "0.30 0.40 0.50" },  { "sill", "0.90 0.90 0.88" },
        { "roof", "0.45 0.25 0.20" }, { "ground", "0.40 0.40 0.38" }, { "metal", "0.20 0.20 0.22" },
    };
    for (size_t m = 0; m < sizeof materials / sizeof materials[0]; ++m) {
        fprintf(mtl, "newmtl %s\nKd %s\n\n", materials[m][0], materials[m][1]);
    }
    fclose(mtl);

    build();
    // The largest density (UV units per metre) at which the islands fit.
    double lo = 0.0, hi = 1.0;
    for (int i = 0; i < 100; ++i) {
        double mid = 0.5 * (lo + hi);
        if (pack(mid)) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    const double density = lo;
    if (!pack(density)) {
        fprintf(stderr, "gen_building: the islands do not fit in the UV tile\n");
        return 1;
    }
    double covered = 0.0;
    int clamped = 0;
    for (int i = 0; i < face_count; ++i) {
        covered += island_area(&faces[i], density);
        clamped += faces[i].width * density < faces[i].size[0] ||
                   faces[i].height * density < faces[i].size[1];
    }
    char summary[512];
    snprintf(summary, sizeof summary,
             "UV layout: %d islands (one per face), coverage %.1f%% of [0,1]^2, density %.4f m "
             "per UV unit = %.2f texels per metre at %d (%.2f cm per texel), gutter %g texels, "
             "%d islands widened to %g texels",
             face_count, 100.0 * covered, 1.0 / density, density * TEXTURE_SIZE, TEXTURE_SIZE,
             100.0 / (density * TEXTURE_SIZE), GUTTER_TEXELS, clamped, MIN_TEXELS);

    snprintf(path, sizeof path, "%s/building.obj", dir);
    FILE *obj = fopen(path, "w");
    if (obj == NULL) {
        perror(path);
        return 1;
    }
    fprintf(obj, "# Default weathering scene: generated by tests/tools/gen_building.c\n");
    fprintf(obj, "# %s\n", summary);
    fprintf(obj, "mtllib building.mtl\n");
    const char *material = NULL;
    int vertex_count = 0;
    for (int b = 0; b < box_count; ++b) {
        if (material == NULL || strcmp(material, boxes[b].material) != 0) {
            fprintf(obj, "usemtl %s\n", boxes[b].material);
            material = boxes[b].material;
        }
        const face *first = &faces[boxes[b].first_face];
        for (int q = 0; q < 6; ++q) {
            for (int k = 0; k < 4; ++k) {
                const double *p = first[q].corner[k];
                fprintf(obj, "v %.4f %.4f %.4f\n", p[0], p[1], p[2]);
            }
        }
        for (int q = 0; q < 6; ++q) {
            for (int k = 0; k < 4; ++k) {
                double uv[2];
                corner_uv(&first[q], k, density, uv);
                fprintf(obj, "vt %.7f %.7f\n", uv[0], uv[1]);
            }
        }
        for (int q = 0; q < 6; ++q) {
            int c = vertex_count + 4 * q + 1;
            fprintf(obj, "f %d/%d %d/%d %d/%d\n", c, c, c + 1, c + 1, c + 2, c + 2);
            fprintf(obj, "f %d/%d %d/%d %d/%d\n", c, c, c + 2, c + 2, c + 3, c + 3);
        }
        vertex_count += 24;
    }
    fclose(obj);
    printf("wrote %s: %d boxes, %d triangles\n", path, box_count, box_count * 12);
    fprintf(stderr, "%s\n", summary);
    return 0;
}
