// test_mesh.c: Assimp import into flat arrays (src/mesh.c).
#include <stdio.h>
#include <string.h>

#include "ensure.h"
#include "mesh.h"

static const char *data_path(const char *name)
{
    static char paths[4][4096];
    static int next;
    char *p = paths[next];
    next = (next + 1) % 4;
    snprintf(p, 4096, "%s/data/%s", ensure_tests_dir(), name);
    return p;
}

static int find_material(const wx_mesh_data *m, const char *name)
{
    for (int k = 0; k < m->material_count; ++k) {
        if (strcmp(m->material_names[k], name) == 0) {
            return k;
        }
    }
    return -1;
}

// World position of vertex v.
static void world(const wx_mesh_data *m, int64_t v, double p[3])
{
    for (int i = 0; i < 3; ++i) {
        p[i] = m->origin[i] + m->positions[3 * v + i];
    }
}

TEST(two_materials_keep_their_names)
{
    wx_mesh_data m;
    wx_error err = { "" };
    ENSURE(wx_mesh_import(data_path("bake_two_materials.obj"), &m, &err) == WX_OK);
    ENSURE(m.triangle_count == 4);
    ENSURE(m.vertex_count == 8); // one aiMesh per material: the shared edge is not shared
    ENSURE(m.material_count == 2);
    int wood = find_material(&m, "Wood"), glass = find_material(&m, "Glass");
    ENSURE(wood >= 0 && glass >= 0);
    ENSURE(m.colors == NULL);
    // Each triangle's material follows its side of x = 0.
    for (int64_t t = 0; t < m.triangle_count; ++t) {
        double cx = 0.0;
        for (int k = 0; k < 3; ++k) {
            double p[3];
            world(&m, m.indices[3 * t + k], p);
            cx += p[0] / 3.0;
        }
        ENSURE(m.materials[t] == (cx < 0.0 ? wood : glass));
    }
    ENSURE_NEAR(m.bounds_min[0], -1.0, 1e-12);
    ENSURE_NEAR(m.bounds_max[0], 1.0, 1e-12);
    ENSURE_NEAR(m.bounds_min[1], -1.0, 1e-12);
    ENSURE_NEAR(m.bounds_max[2], 0.0, 1e-12);
    ENSURE_NEAR(m.origin[0], 0.0, 1e-12);
    for (int64_t v = 0; v < m.vertex_count; ++v) {
        ENSURE_NEAR(m.normals[3 * v + 2], 1.0, 1e-6); // generated: the quads face +z
    }
    wx_mesh_data_free(&m);
    ENSURE(m.positions == NULL && m.material_names == NULL);
}

TEST(box_gets_flat_generated_normals)
{
    wx_mesh_data m;
    wx_error err = { "" };
    ENSURE(wx_mesh_import(data_path("bake_box.obj"), &m, &err) == WX_OK);
    ENSURE(m.triangle_count == 12);
    // Edges of 90 degrees are not smoothed: 4 vertices per face after joining.
    ENSURE(m.vertex_count == 24);
    for (int64_t t = 0; t < m.triangle_count; ++t) {
        // All three normals equal the face's outward axis: the centroid's largest coordinate.
        double c[3] = { 0, 0, 0 };
        for (int k = 0; k < 3; ++k) {
            double p[3];
            world(&m, m.indices[3 * t + k], p);
            for (int i = 0; i < 3; ++i) {
                c[i] += p[i] / 3.0;
            }
        }
        int axis = 0;
        for (int i = 1; i < 3; ++i) {
            axis = fabs(c[i]) > fabs(c[axis]) ? i : axis;
        }
        for (int k = 0; k < 3; ++k) {
            const float *n = &m.normals[3 * m.indices[3 * t + k]];
            for (int i = 0; i < 3; ++i) {
                double want = i == axis ? (c[axis] > 0 ? 1.0 : -1.0) : 0.0;
                ENSURE_NEAR(n[i], want, 1e-6);
            }
        }
    }
    ENSURE(m.material_count == 1); // Assimp's DefaultMaterial
    wx_mesh_data_free(&m);
}

TEST(ply_vertex_colours)
{
    wx_mesh_data m;
    wx_error err = { "" };
    ENSURE(wx_mesh_import(data_path("bake_colors.ply"), &m, &err) == WX_OK);
    ENSURE(m.triangle_count == 2);
    ENSURE(m.vertex_count == 4);
    ENSURE(m.colors != NULL);
    ENSURE(m.material_count == 1 && m.material_colored[0]);
    for (int64_t v = 0; v < m.vertex_count; ++v) {
        double p[3];
        world(&m, v, p);
        const float *c = &m.colors[4 * v];
        if (p[1] < 0.0) {
            ENSURE_NEAR(c[0], 51.0 / 255.0, 1e-6);
            ENSURE_NEAR(c[1], 204.0 / 255.0, 1e-6);
        } else {
            ENSURE_NEAR(c[0], 1.0, 1e-6);
            ENSURE_NEAR(c[1], 0.0, 1e-6);
        }
        ENSURE_NEAR(c[2], 0.0, 1e-6);
    }
    wx_mesh_data_free(&m);
}

TEST(gltf_node_transforms_are_applied)
{
    // parent: translation (10,0,0); child: scale 2, 90 degrees about +Y. The
    // triangle (0,0,0) (1,0,0) (0,1,0) with normal +z lands on (10,0,0)
    // (10,0,-2) (10,2,0) with normal +x.
    wx_mesh_data m;
    wx_error err = { "" };
    ENSURE(wx_mesh_import(data_path("bake_transform.gltf"), &m, &err) == WX_OK);
    ENSURE(m.triangle_count == 1 && m.vertex_count == 3);
    ENSURE(find_material(&m, "Painted") == 0);
    const double want[3][3] = { { 10, 0, 0 }, { 10, 0, -2 }, { 10, 2, 0 } };
    for (int k = 0; k < 3; ++k) {
        double p[3];
        world(&m, m.indices[k], p);
        for (int i = 0; i < 3; ++i) {
            ENSURE_NEAR(p[i], want[k][i], 1e-5);
        }
        const float *n = &m.normals[3 * m.indices[k]];
        ENSURE_NEAR(n[0], 1.0, 1e-5);
        ENSURE_NEAR(n[1], 0.0, 1e-5);
        ENSURE_NEAR(n[2], 0.0, 1e-5);
    }
    ENSURE_NEAR(m.origin[0], 10.0, 1e-5);
    ENSURE_NEAR(m.origin[1], 1.0, 1e-5);
    ENSURE_NEAR(m.origin[2], -1.0, 1e-5);
    wx_mesh_data_free(&m);
}

TEST(missing_file_names_it)
{
    wx_mesh_data m;
    wx_error err = { "" };
    const char *path = data_path("bake_no_such_mesh.obj");
    ENSURE(wx_mesh_import(path, &m, &err) == WX_BAD_INPUT);
    ENSURE(ensure_contains(err.message, "bake_no_such_mesh.obj"));
    ENSURE(ensure_contains(err.message, "cannot import"));
    ENSURE(m.positions == NULL && m.triangle_count == 0);
    wx_mesh_data_free(&m);
}

TEST(unsupported_file_names_it)
{
    wx_mesh_data m;
    wx_error err = { "" };
    ENSURE(wx_mesh_import(data_path("bake_not_a_mesh.txt"), &m, &err) == WX_BAD_INPUT);
    ENSURE(ensure_contains(err.message, "bake_not_a_mesh.txt"));
    wx_mesh_data_free(&m);
}

TEST(lines_only_give_no_triangles)
{
    const char *path = ensure_write_file(ensure_tmpdir(), "lines.obj",
                                         "v 0 0 0\nv 1 0 0\nv 1 1 0\nl 1 2\nl 2 3\n");
    wx_mesh_data m;
    wx_error err = { "" };
    wx_result r = wx_mesh_import(path, &m, &err);
    // Assimp may refuse a file without faces; either way nothing is drawn.
    ENSURE(r == WX_OK || r == WX_BAD_INPUT);
    ENSURE(m.triangle_count == 0);
    wx_mesh_data_free(&m);
}

int main(void)
{
    RUN(two_materials_keep_their_names);
    RUN(box_gets_flat_generated_normals);
    RUN(ply_vertex_colours);
    RUN(gltf_node_transforms_are_applied);
    RUN(missing_file_names_it);
    RUN(unsupported_file_names_it);
    RUN(lines_only_give_no_triangles);
    return ensure_summary();
}
