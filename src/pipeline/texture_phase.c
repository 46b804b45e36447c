// texture_phase.c: the scene's <TextureMap>s (texture_phase.h).
#include "pipeline/texture_phase.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/progress.h"
#include "gather/gather.h"
#include "io/exr.h"
#include "io/png_preview.h"
#include "model/image.h"
#include "model/naming.h"
#include "pipeline/load.h"
#include "pipeline/outputs.h"
#include "pipeline/tiles.h"

// The arrays the sampling reads, copied: the bake releases the geometry's.
static wx_result copy_mesh(const wx_mesh_data *from, int uv, wx_mesh_data *to, wx_error *err)
{
    memset(to, 0, sizeof *to);
    size_t nv = (size_t)from->vertex_count, nt = (size_t)from->triangle_count;
    to->vertex_count = from->vertex_count;
    to->triangle_count = from->triangle_count;
    memcpy(to->origin, from->origin, sizeof to->origin);
    to->positions = malloc(3 * nv * sizeof *to->positions + 1);
    to->normals = malloc(3 * nv * sizeof *to->normals + 1);
    to->indices = malloc(3 * nt * sizeof *to->indices + 1);
    to->uvs[uv] = malloc(2 * nv * sizeof *to->uvs[uv] + 1);
    if (to->positions == NULL || to->normals == NULL || to->indices == NULL ||
        to->uvs[uv] == NULL || from->uvs[uv] == NULL) {
        wx_mesh_data_free(to);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "texture: out of memory for the mesh");
    }
    memcpy(to->positions, from->positions, 3 * nv * sizeof *to->positions);
    memcpy(to->normals, from->normals, 3 * nv * sizeof *to->normals);
    memcpy(to->indices, from->indices, 3 * nt * sizeof *to->indices);
    memcpy(to->uvs[uv], from->uvs[uv], 2 * nv * sizeof *to->uvs[uv]);
    if (from->creases != NULL) {
        to->creases = malloc(nt + 1);
        if (to->creases == NULL) {
            wx_mesh_data_free(to);
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "texture: out of memory for the mesh");
        }
        memcpy(to->creases, from->creases, nt);
    }
    return WX_OK;
}

// The surface area of a mesh.
static double mesh_area(const wx_mesh_data *mesh)
{
    double area = 0.0;
    for (int64_t k = 0; k < mesh->triangle_count; ++k) {
        const uint32_t *idx = &mesh->indices[3 * k];
        const float *a = &mesh->positions[3 * (size_t)idx[0]];
        const float *b = &mesh->positions[3 * (size_t)idx[1]];
        const float *c = &mesh->positions[3 * (size_t)idx[2]];
        double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
        double e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
        double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2];
        double z = e1[0] * e2[1] - e1[1] * e2[0];
        area += 0.5 * sqrt(x * x + y * y + z * z);
    }
    return area;
}

void wx_textures_find_tiles(wx_scene *scene, const wx_geometry *geometry)
{
    for (int i = 0; i < scene->texture_count; ++i) {
        wx_texture_map *t = &scene->textures[i];
        const wx_mesh_data *mesh = &geometry->meshes[t->mesh].data;
        wx_uv_survey survey;
        wx_error err;
        if (t->tiles != WX_TILES_UDIM ||
            wx_uv_survey_build(mesh, t->uv, t->width, t->height, &survey, &err) != WX_OK) {
            continue; // a missing channel: the geometry's import refused it already
        }
        memcpy(t->udim, survey.udim, sizeof t->udim);
        t->udim_count = survey.udim_count;
        t->udim_known = true;
    }
}

// "1001, 1002, 1011" (the first few, then "..."), for messages.
static void tile_list(const wx_texture_map *t, char *out, size_t cap)
{
    out[0] = '\0';
    int shown = 0;
    for (int f = 0; f < t->udim_count; ++f) {
        char number[16];
        if (shown == 8) {
            wx_list_append(out, cap, "...");
            break;
        }
        snprintf(number, sizeof number, "%d", WX_UDIM_FIRST + wx_texture_file_tile(t, f));
        wx_list_append(out, cap, number);
        shown++;
    }
}

// What `run` says of a texture's layout (as `info` does): coverage, overlaps,
// triangles outside, left out, or no texel at all.
static void report_layout(const wx_scene *scene, const wx_run_def *opts,
                          const wx_texture_target *t)
{
    const wx_texture_map *def = t->def;
    const wx_mesh *mesh = &scene->meshes[def->mesh];
    const int64_t triangles = t->mesh.triangle_count;
    int64_t covered = 0, padded = 0, overlapping = 0;
    for (int f = 0; f < t->file_count; ++f) {
        covered += t->files[f].raster.covered;
        padded += t->files[f].raster.padded;
        overlapping += t->files[f].raster.overlapping;
    }
    double texels = (double)def->width * (double)def->height * (t->file_count > 0 ? t->file_count : 1);
    if (def->tiles == WX_TILES_UDIM) {
        char tiles[128];
        tile_list(def, tiles, sizeof tiles);
        wx_note(opts->quiet,
                "texture %s: %d UDIM tile%s (%s) of %d x %d texels over UV channel %d of '%s', "
                "%.1f%% covered (%lld texels), %lld padded",
                def->file, t->file_count, t->file_count == 1 ? "" : "s", tiles, def->width,
                def->height, def->uv, wx_mesh_display_name(scene, mesh),
                100.0 * (double)covered / texels, (long long)covered, (long long)padded);
    } else {
        wx_note(opts->quiet,
                "texture %s: %d x %d texels over UV channel %d of '%s', %.1f%% covered "
                "(%lld texels), %lld padded",
                def->file, def->width, def->height, def->uv, wx_mesh_display_name(scene, mesh),
                100.0 * (double)covered / texels, (long long)covered, (long long)padded);
    }
    if (overlapping > 0) {
        wx_warn(opts->quiet,
                "%s:%d: texture %s: %lld texels lie in more than one triangle of the UV "
                "layout (overlapping UVs): each takes the first triangle's surface point",
                scene->path, def->line, def->file, (long long)overlapping);
    }
    // Every file's raster counts the same triangles: the first's speak for all
    // (a UDIM texture without a tile asks the survey).
    int64_t outside = 0, unusable = 0;
    wx_uv_survey survey;
    wx_error ignored;
    if (t->file_count > 0) {
        outside = t->files[0].raster.triangles_outside;
        unusable = t->files[0].raster.triangles_unusable;
    } else if (wx_uv_survey_build(&t->mesh, def->uv, def->width, def->height, &survey,
                                  &ignored) == WX_OK) {
        outside = survey.triangles_outside_udim;
        unusable = survey.triangles_unusable;
    }
    if (outside > 0 && def->tiles == WX_TILES_CLIP) {
        wx_warn(opts->quiet,
                "%s:%d: texture %s: %lld of %lld triangles reach outside the [0,1] UV tile; "
                "only the tile is written (tiles=\"clip\")",
                scene->path, def->line, def->file, (long long)outside, (long long)triangles);
    } else if (outside > 0 && def->tiles == WX_TILES_REPEAT) {
        wx_note(opts->quiet,
                "%s:%d: texture %s: %lld of %lld triangles reach outside the [0,1] UV tile; "
                "they wrap onto it as a renderer's REPEAT reads them",
                scene->path, def->line, def->file, (long long)outside, (long long)triangles);
    } else if (outside > 0) {
        wx_warn(opts->quiet,
                "%s:%d: texture %s: %lld of %lld triangles reach outside the UDIM tiles 1001 "
                "to 2000 (u in [0,10], v in [0,100]); their parts there are not written",
                scene->path, def->line, def->file, (long long)outside, (long long)triangles);
    }
    if (unusable > 0) {
        wx_warn(opts->quiet,
                "%s:%d: texture %s: %lld of %lld triangles have no usable UVs (a UV that is not "
                "a finite number or lies beyond 65536, all three corners at one point or on one "
                "line in UV: an OBJ face without vt%s); they cover no texel",
                scene->path, def->line, def->file, (long long)unusable, (long long)triangles,
                def->tiles == WX_TILES_CLIP ? "" : "; or more than 64 UV tiles spanned");
    }
    if (covered == 0) {
        wx_warn(opts->quiet,
                def->tiles == WX_TILES_UDIM
                    ? "%s:%d: texture %s: no texel centre of any UDIM tile lies inside a triangle "
                      "of the UV layout: no file is written"
                    : "%s:%d: texture %s: no texel centre lies inside a triangle of the UV layout",
                scene->path, def->line, def->file);
    }
}

wx_result wx_textures_prepare(const wx_scene *scene, const wx_geometry *geometry,
                              const wx_run_def *opts, wx_textures *out, wx_error *err)
{
    memset(out, 0, sizeof *out);
    if (scene->texture_count == 0) {
        return WX_OK;
    }
    wx_result r = WX_OK;
    out->items = calloc((size_t)scene->texture_count, sizeof *out->items);
    if (r == WX_OK && out->items == NULL) {
        r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (textures)");
    }
    for (int i = 0; i < scene->texture_count && r == WX_OK; ++i) {
        const wx_texture_map *def = &scene->textures[i];
        wx_texture_target *t = &out->items[i];
        out->count = i + 1;
        t->def = def;
        assert(def->tiles != WX_TILES_UDIM || def->udim_known); // wx_textures_find_tiles
        r = copy_mesh(&geometry->meshes[def->mesh].data, def->uv, &t->mesh, err);
        const int files = wx_texture_file_count(def);
        t->files = r == WX_OK ? calloc((size_t)files + 1, sizeof *t->files) : NULL;
        if (r == WX_OK && t->files == NULL) {
            r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (textures)");
        }
        int64_t covered = 0;
        for (int f = 0; f < files && r == WX_OK; ++f) {
            wx_uv_raster_def rd = { .mesh = &t->mesh,
                                    .uv = def->uv,
                                    .tiles = def->tiles,
                                    .udim = wx_texture_file_tile(def, f),
                                    .width = def->width,
                                    .height = def->height,
                                    .padding = def->padding };
            t->files[f].udim = rd.udim;
            r = wx_uv_raster_build(&rd, &t->files[f].raster, err);
            t->file_count = r == WX_OK ? f + 1 : f;
            covered += r == WX_OK ? t->files[f].raster.covered : 0;
        }
        if (r != WX_OK) {
            wx_error_prefix(err, "%s:%d: <TextureMap file=\"%s\">", scene->path, def->line,
                            def->file);
            break;
        }
        t->texel = covered > 0 ? (float)sqrt(mesh_area(&t->mesh) / (double)covered) : 1.0f;
        report_layout(scene, opts, t);
    }
    if (r != WX_OK) {
        wx_textures_free(out);
    }
    return r;
}

void wx_textures_free(wx_textures *textures)
{
    for (int i = 0; i < textures->count; ++i) {
        wx_texture_target *t = &textures->items[i];
        wx_mesh_data_free(&t->mesh);
        for (int f = 0; f < t->file_count; ++f) {
            wx_uv_raster_free(&t->files[f].raster);
        }
        free(t->files);
    }
    free(textures->items);
    memset(textures, 0, sizeof *textures);
}

// ---------------------------------------------------------------------------
// Writing.

// The mask of every channel on every input camera's own texels, for one setting
// of the smoothing: planes[k * channels + c].
typedef struct camera_planes {
    const wx_texture_map *key; // the smoothing of this TextureMap
    float **planes;
    wx_gather_stats noise; // the first substance's gathers, summed over the cameras
} camera_planes;

static bool same_smoothing(const wx_texture_map *a, const wx_texture_map *b)
{
    return a->adaptive == b->adaptive && a->radius == b->radius && a->noise == b->noise &&
           a->max_radius == b->max_radius;
}

// The note of the final texture when much of its surface keeps more noise than
// it asks for (as the mask's, gather_phase.c): the first substance's capped
// texels over every input camera's own texels, which the texture samples.
static void note_capped(const wx_run_def *opts, const wx_texture_map *key,
                        const wx_gather_stats *sum)
{
    if (!key->adaptive || sum->surface_texels <= 0 ||
        10 * sum->capped_texels <= sum->surface_texels) {
        return;
    }
    char radius[64];
    if (key->max_radius > 0.0f) {
        snprintf(radius, sizeof radius, "%g m", (double)key->max_radius);
    } else {
        snprintf(radius, sizeof radius, "%g texels of each input camera",
                 (double)WX_DEFAULT_MAX_RADIUS_TEXELS);
    }
    wx_note(opts->quiet,
            "texture %s: %.0f%% of the surface its input cameras see holds fewer than the %.0f "
            "impacts within maxRadius (%s) that %g%% noise needs: its noise there is about "
            "%.2g%% (the median); where that shows, fly more particles or raise the "
            "TextureMap's maxRadius",
            key->file, 100.0 * (double)sum->capped_texels / (double)sum->surface_texels,
            sum->target_hits, radius, 100.0 * (double)key->noise, 100.0 * sum->capped_noise);
}

static wx_result compute_planes(const wx_scene *scene, const wx_run_def *opts,
                                const wx_maps *in_maps, wx_gather_view *views, int channels,
                                const wx_texture_map *key, bool note, float **planes,
                                wx_gather_stats *sum, wx_error *err)
{
    const int k_count = scene->input_count;
    wx_result r = WX_OK;
    int k = 0;
    wx_gather_stats st;
    memset(sum, 0, sizeof *sum);
    // The mask on every input camera's texels, a channel at a time.
    wx_progress progress;
    wx_progress_begin(&progress, "texture", (int64_t)k_count * channels, opts->quiet);
    for (int cam = 0; cam < scene->camera_count && r == WX_OK; ++cam) {
        const wx_scene_camera *sc = &scene->cameras[cam];
        if (sc->is_output) {
            continue;
        }
        const wx_maps *m = &in_maps[k];
        float frame_w, frame_h;
        wx_camera_frame_size(&sc->camera, &frame_w, &frame_h);
        for (int c = 0; c < channels && r == WX_OK; ++c) {
            wx_gather_views_of_substance(views, in_maps, k_count, c);
            float **plane = &planes[(size_t)k * (size_t)channels + (size_t)c];
            *plane = malloc((size_t)m->width * (size_t)m->height * sizeof **plane + 1);
            if (*plane == NULL) {
                r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "texture: out of memory");
                break;
            }
            wx_gather_def def = wx_default_gather_def();
            def.target = wx_target_from_camera(&sc->camera, m);
            def.inputs = views;
            def.input_count = k_count;
            def.radius = key->radius;
            def.adaptive = key->adaptive;
            def.noise = key->noise;
            // By default the largest radius is as many of this camera's texels as
            // the mask's default is of output texels.
            def.max_radius = key->max_radius > 0.0f
                                 ? key->max_radius
                                 : WX_DEFAULT_MAX_RADIUS_TEXELS * frame_w / (float)m->width;
            def.threads = opts->threads;
            def.quiet = true;
            r = wx_gather_compute(&def, *plane, c == 0 ? &st : NULL, err);
            if (r == WX_OK && c == 0) {
                sum->surface_texels += st.surface_texels;
                sum->capped_texels += st.capped_texels;
                sum->target_hits = st.target_hits;
                for (int b = 0; b < WX_NOISE_BINS; ++b) {
                    sum->capped_noise_bins[b] += st.capped_noise_bins[b];
                }
            }
            wx_progress_update(&progress, (int64_t)k * channels + c + 1);
        }
        k++;
    }
    wx_progress_end(&progress);
    sum->capped_noise = wx_noise_bins_median(sum->capped_noise_bins);
    if (r == WX_OK && note) {
        note_capped(opts, key, sum);
    }
    return r;
}

static void free_planes(camera_planes *cache, int count, int planes)
{
    for (int i = 0; i < count; ++i) {
        for (int p = 0; cache[i].planes != NULL && p < planes; ++p) {
            free(cache[i].planes[p]);
        }
        free(cache[i].planes);
    }
    free(cache);
}

// The derived masks at a texture's covered texels that are seen (channels
// after the substances'), at the surface points the sampling made
// (position, normal), the substances' sampled values for the Combines.
static wx_result texture_masks(const wx_scene *scene, const wx_run_def *opts,
                               wx_mask_context *masks, int slot, const wx_texture_target *t,
                               const wx_uv_raster *ras, wx_image *image, const double *position,
                               const float *normal, wx_error *err)
{
    const size_t texels = (size_t)ras->width * (size_t)ras->height;
    const float *seen = image->channels[image->channel_count - 1];
    unsigned char *valid = malloc(texels + 1);
    if (valid == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "texture: out of memory (masks)");
    }
    for (size_t i = 0; i < texels; ++i) {
        valid[i] = seen[i] > 0.5f; // seen implies covered: its point was made
    }
    wx_mask_points points = { .width = ras->width,
                              .height = ras->height,
                              .position = position,
                              .normal = normal,
                              .valid = valid,
                              .texel = t->texel };
    const int S = image->channel_count - 1 - scene->mask_count;
    wx_result r = wx_masks_at_points(scene, opts, masks, slot, &points,
                                     (const float *const *)image->channels, image->channels + S,
                                     err);
    free(valid);
    return r;
}

// One file of a texture (the texture, or one UDIM tile): sampled into `image`
// (its channels allocated) and written with its previews (frame 0).
static wx_result write_texture(const wx_scene *scene, const wx_run_def *opts,
                               const wx_texture_target *t, const wx_texture_file *file,
                               const wx_gather_view *views, float *const *planes,
                               wx_mask_context *masks, int slot, int frame,
                               char names[][WX_NAME_MAX], int channels, wx_phase_detail *detail,
                               wx_error *err)
{
    const wx_texture_map *def = t->def;
    const wx_uv_raster *ras = &file->raster;
    const char *channel_names[WX_IMAGE_MAX_CHANNELS];
    for (int c = 0; c < channels; ++c) {
        channel_names[c] = names[c];
    }
    // The file's own name: the texture's, or its tile's BASE.TTTT.exr; frames
    // and previews are named from it.
    char own[WX_OUTPUT_NAME_MAX], path[WX_PATH_MAX], name[WX_OUTPUT_NAME_MAX];
    if (file->udim >= 0) {
        wx_tile_name(def->file, file->udim, own, sizeof own);
    } else {
        snprintf(own, sizeof own, "%s", def->file);
    }
    wx_frame_name(own, frame, name, sizeof name);
    wx_result r = wx_output_path(scene, opts, frame > 0 ? name : own, path, err);
    wx_image *image = calloc(1, sizeof *image);
    if (image == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "texture: out of memory");
    }
    double t0 = wx_now_s();
    if (r == WX_OK) {
        r = wx_image_alloc(image, def->width, def->height, channels, channel_names, err);
    }
    // The surface points, kept for the derived masks.
    const size_t texels = (size_t)def->width * (size_t)def->height;
    double *position = NULL;
    float *normal = NULL;
    const bool enclosing = masks != NULL && masks->ready;
    if (r == WX_OK && (scene->mask_count > 0 || enclosing || scene->tile.present)) {
        position = calloc(3 * texels, sizeof *position);
        normal = calloc(3 * texels, sizeof *normal);
        if (position == NULL || normal == NULL) {
            r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "texture: out of memory (masks)");
        }
    }
    if (r == WX_OK) {
        wx_texture_def td = { .mesh = &t->mesh,
                              .uv = def->uv,
                              .raster = ras,
                              .inputs = views,
                              .input_count = scene->input_count,
                              .smoothed = (const float *const *)planes,
                              .channels = channels - 1 - scene->mask_count,
                              .threads = opts->threads,
                              .position = position,
                              .normal = normal };
        r = wx_texture_sample(&td, image->channels, image->channels[channels - 1], NULL, err);
    }
    // With layers, faces the collider encloses are not seen (nor their values).
    if (r == WX_OK && enclosing) {
        float *seen = image->channels[channels - 1];
        wx_mask_points points = {
            .width = ras->width, .height = ras->height, .position = position, .normal = normal
        };
        wx_masks_unsee_enclosed(&masks->collider, &points, seen, opts->threads);
        for (size_t i = 0; i < texels; ++i) {
            for (int c = 0; c + 1 < channels && !(seen[i] > 0.0f); ++c) {
                image->channels[c][i] = 0.0f;
            }
        }
    }
    // A tile's run writes only the points its <Tile> owns (docs/tiles.md).
    if (r == WX_OK) {
        wx_tile_restrict_points(scene, position, image->channels[channels - 1], image);
    }
    // The derived masks at the texels whose point is seen, then the padding of
    // every channel.
    if (r == WX_OK && scene->mask_count > 0) {
        r = texture_masks(scene, opts, masks, slot, t, ras, image, position, normal, err);
    }
    free(position);
    free(normal);
    if (r == WX_OK) {
        wx_texture_pad(ras, image->channels, channels);
    }
    double t1 = wx_now_s();
    if (r == WX_OK) {
        wx_image_set_string(image, "weatheringMesh",
                            wx_mesh_display_name(scene, &scene->meshes[def->mesh]));
        char uv[16];
        snprintf(uv, sizeof uv, "%d", def->uv);
        wx_image_set_string(image, "weatheringUVChannel", uv);
        if (file->udim >= 0) {
            char tile[16];
            snprintf(tile, sizeof tile, "%d", WX_UDIM_FIRST + file->udim);
            wx_image_set_string(image, "weatheringUDIMTile", tile);
        }
        image->threads = opts->threads;
        r = wx_image_check_finite(image, path, err);
    }
    if (r == WX_OK) {
        r = wx_exr_write(path, image, err);
    }
    // Previews: transparent where no texel holds a value.
    float *alpha = NULL;
    if (r == WX_OK && frame == 0) {
        alpha = malloc(texels * sizeof *alpha);
        if (alpha == NULL) {
            r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "texture: out of memory (preview)");
        }
        for (size_t i = 0; alpha != NULL && i < texels; ++i) {
            alpha[i] = ras->source[i] >= 0 ? 1.0f : INFINITY;
        }
    }
    // One preview per channel of the mask (`seen` has none).
    char previews[WX_MAX_PREVIEWS][WX_OUTPUT_NAME_MAX];
    int preview_count = r == WX_OK && frame == 0 ? wx_preview_names(scene, own, previews) : 0;
    for (int c = 0; c < preview_count && r == WX_OK; ++c) {
        r = wx_output_path(scene, opts, previews[c], path, err);
        if (r == WX_OK) {
            r = wx_preview_write_png(path, image->channels[c], alpha, def->width, def->height,
                                     err);
        }
    }
    free(alpha);
    if (detail != NULL) {
        detail->compute += t1 - t0;
        detail->write += wx_now_s() - t1;
    }
    wx_image_free(image);
    free(image);
    return r;
}

wx_result wx_textures_write(const wx_scene *scene, const wx_run_def *opts,
                            const wx_textures *textures, const wx_maps *in_maps,
                            wx_mask_context *masks, int frame, wx_phase_detail *detail,
                            wx_noise_report *noise, wx_error *err)
{
    if (textures == NULL || textures->count == 0) {
        return WX_OK;
    }
    char names[WX_IMAGE_MAX_CHANNELS][WX_NAME_MAX];
    const int channels = wx_texture_channels(scene, names);
    const int substances = scene->substance_count > 0 ? scene->substance_count : 1;
    const int planes_per_key = scene->input_count * substances;
    wx_gather_view *views = calloc((size_t)scene->input_count + 1, sizeof *views);
    camera_planes *cache = calloc((size_t)textures->count, sizeof *cache);
    if (views == NULL || cache == NULL) {
        free(views);
        free(cache);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "texture: out of memory");
    }
    int k = 0;
    for (int c = 0; c < scene->camera_count; ++c) {
        if (!scene->cameras[c].is_output) {
            views[k] = wx_gather_view_from_maps(&scene->cameras[c].camera, &in_maps[k]);
            k++;
        }
    }
    int cached = 0;
    wx_result r = WX_OK;
    for (int i = 0; i < textures->count && r == WX_OK; ++i) {
        const wx_texture_target *t = &textures->items[i];
        if (!wx_texture_writes_frame(t->def, frame)) {
            continue;
        }
        int slot = 0;
        while (slot < cached && !same_smoothing(cache[slot].key, t->def)) {
            ++slot;
        }
        if (slot == cached) {
            double t0 = wx_now_s();
            cache[slot].key = t->def;
            cache[slot].planes = calloc((size_t)planes_per_key + 1, sizeof *cache[slot].planes);
            cached++;
            r = cache[slot].planes != NULL
                    ? compute_planes(scene, opts, in_maps, views, substances, t->def, frame == 0,
                                     cache[slot].planes, &cache[slot].noise, err)
                    : wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "texture: out of memory");
            if (detail != NULL) {
                detail->compute += wx_now_s() - t0;
            }
        }
        if (r == WX_OK && frame == 0 && t->def->adaptive) {
            wx_noise_figures figures =
                wx_gather_noise_figures(t->def->file, t->def->noise, &cache[slot].noise);
            r = wx_noise_report_add(noise, &figures, err);
        }
        for (int f = 0; f < t->file_count && r == WX_OK; ++f) {
            r = write_texture(scene, opts, t, &t->files[f], views, cache[slot].planes, masks,
                              wx_mask_slot_texture(scene, i, f), frame, names, channels, detail,
                              err);
        }
        if (r != WX_OK) {
            wx_error_prefix(err, "texture %s", t->def->file);
        }
    }
    free_planes(cache, cached, planes_per_key);
    free(views);
    return r;
}

int64_t wx_texture_bytes(const wx_scene *scene, const wx_texture_map *t, int64_t camera_texels)
{
    char names[WX_IMAGE_MAX_CHANNELS][WX_NAME_MAX];
    const int64_t channels = wx_texture_channels(scene, names);
    const int64_t texels = (int64_t)t->width * t->height;
    // The raster (triangle and source) and its build's count; the image's
    // channels and the preview's alpha; the compressed chunks written (at most
    // the image again); every channel but seen on every input camera, and the
    // gather's planes for one of them (the adaptive pass's 15 floats a texel).
    // The derived masks' points (and with layers the enclosed faces' test's):
    // a double position, a normal and a flag.
    const int64_t points =
        scene->mask_count > 0 || wx_scene_has_layers(scene) ? texels * (24 + 12 + 1) : 0;
    return points + texels * (4 + 4 + 1) + texels * 4 * (channels + 1) + texels * 4 * channels +
           camera_texels * 4 * (channels - 1) + camera_texels / (scene->input_count > 0 ?
                                                                 scene->input_count : 1) * 4 * 15;
}
