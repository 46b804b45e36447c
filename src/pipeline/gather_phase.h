// gather_phase.h: the `gather` phase: the input cameras' maps and dirt read (or
// given in memory by a simulation that just ran), the output camera's maps
// read, the mask computed (gather/gather.c) and written with its preview.
#ifndef WX_GATHER_PHASE_H
#define WX_GATHER_PHASE_H

#include "core/error.h"
#include "gather/gather.h"
#include "model/maps.h"
#include "model/scene.h"
#include "model/stats.h"
#include "pipeline/pipeline.h"

struct wx_textures;     // pipeline/texture_phase.h
struct wx_mask_context; // pipeline/masks_phase.h

/// Checks what the gather would refuse about the scene, before any work: the
/// output camera's second-pass radius must fit the gather's neighbourhood limit
/// (WX_CAUSE_BAD_VALUE, "scene.xml:LINE: <OutputMap> of camera 'NAME': ...").
/// A scene without an output camera passes (the command says it needs one or
/// a TextureMap).
wx_result wx_gather_check(const wx_scene *scene, wx_error *err);

/// The `gather` phase: loads the output camera's depth and normal maps and, for
/// every input camera, its depth and normal maps and the dirt map `simulate`
/// left in opts->out_dir (<camera>_dirt.exr; when there is none, the camera's
/// dirt map from the scene, with a note on stderr unless quiet), computes the
/// mask and writes opts->out_dir/<output_file> (EXR, channel Y, with the camera
/// in its header) and the PNG preview beside it (extension replaced by .png).
/// The mask only: TextureMaps need their meshes, which `run` and `gather`
/// import (wx_run_phases); the viewer, which links no mesh importer, calls this.
wx_result wx_gather_scene(const wx_scene *scene, const wx_run_def *opts, wx_error *err);

/// The `gather` phase with the input cameras' maps already in memory (one per
/// input camera in scene order: depth, normal and the dirt to gather): reads
/// the output camera's maps (or takes `out_maps`, its depth and normal, when
/// not NULL), computes and writes the mask and its preview, then every
/// TextureMap of `textures` (may be NULL: none; texture_phase.h). `masks` is
/// the derived masks' context (masks_phase.h) made from the same in_maps and
/// kept by the caller over several frames, or NULL: one is made for this call.
/// `detail` (may be NULL) gets the read, compute and write times, `noise`
/// (may be NULL) the figures of every output smoothed adaptively.
wx_result wx_gather_maps(const wx_scene *scene, const wx_run_def *opts, const wx_maps *in_maps,
                         const wx_maps *out_maps, const struct wx_textures *textures,
                         struct wx_mask_context *masks, wx_phase_detail *detail,
                         wx_noise_report *noise, wx_error *err);

/// wx_gather_maps for frame `frame` of an image sequence (docs/design.md
/// section 10): frame 0 writes the final BASE.exr and its previews, frame k > 0
/// BASE.NNNN.exr (k on four digits) without previews, for the mask when its
/// `every` divides k and for each TextureMap whose `every` does.
wx_result wx_gather_frame(const wx_scene *scene, const wx_run_def *opts, const wx_maps *in_maps,
                          const wx_maps *out_maps, const struct wx_textures *textures,
                          struct wx_mask_context *masks, int frame, wx_phase_detail *detail,
                          wx_noise_report *noise, wx_error *err);

#endif
