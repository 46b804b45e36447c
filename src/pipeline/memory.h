// memory.h: the memory a run needs at its peak, estimated from the scene before
// any work, the memory the process may still use, and the check that refuses a
// run that would not fit (docs/reliability.md).
#ifndef WX_MEMORY_H
#define WX_MEMORY_H

#include <stdbool.h>

#include "core/error.h"
#include "model/geometry.h"
#include "model/scene.h"

/// Memory a run needs at its peak, estimated before work starts from the scene
/// alone (docs/reliability.md): the program itself, plus the largest of its
/// phases (they run one after the other; each frees what the next does not use).
typedef struct wx_memory_need {
    double baseline_bytes;     ///< the program and its libraries (WX_MEMORY_BASELINE)
    double mesh_bytes;         ///< importing the meshes (mesh_import_bytes in memory.c)
    double smooth_bytes;       ///< the meshes' smooth surfaces (in mesh_bytes, and left behind)
    double bake_bytes;         ///< the bake: GL context, framebuffer, images being written, meshes
    double sim_map_bytes;      ///< the simulation's maps, collider and dirt (without particles)
    double frame_bytes;        ///< part of sim_map_bytes: a frame of the mask's sequence
    double particles;          ///< particles the emitters emit over all the iterations
    /// At most this many alive at once: per emitter, what it emits in the
    /// longest a particle can live (wx_memory_particles_alive).
    double particles_alive;
    double bytes_per_particle; ///< WX_BYTES_PER_PARTICLE, + WX_BYTES_PER_PARTICLE_LOAD per
                               ///< substance beyond the first
    double particle_bytes;     ///< particles_alive x bytes_per_particle
    double gather_bytes;       ///< the gather: the maps it reads, its planes, the files it writes
    /// TextureMaps (docs/texture.md): their UV rasters, held from the start of
    /// the run to its end, and the largest one's writing (its image and the
    /// mask on every input camera), part of gather_bytes and of a frame's.
    double texture_raster_bytes;
    double texture_write_bytes;
    double total_bytes;        ///< baseline + the largest phase
    const char *phase;         ///< the largest phase: "bake", "simulation" or "gather"
    int substances;            ///< the scene's substances (1 without <Substances>)
    int camera_line;           ///< scene line of the camera with the largest maps
    int emitter_line;          ///< scene line of the emitter with the most particles
    int mesh_line;             ///< scene line of the largest mesh file
} wx_memory_need;

/// Bytes per input texel of the derived masks' collider: its depth copy, the
/// coarse pyramid's levels and the fine test's 3 x 3 bound (near3), and on
/// curved surfaces the cells' curvatures and dips (5).
#define WX_MASK_COLLIDER_BYTES_PER_TEXEL 15.0

/// The program's own memory before any scene data (code, libraries, heaps).
#define WX_MEMORY_BASELINE (64.0 * 1024.0 * 1024.0)
/// The GL context and llvmpipe's own buffers in the bake.
#define WX_BAKE_CONTEXT_BYTES (40.0 * 1024.0 * 1024.0)
/// What the renderer (LLVM's code and caches) keeps after the bake, counted in
/// the phases that follow it in the same run (measured: Spot's run peaks 57 MB
/// above its gather alone).
#define WX_BAKE_RESIDUE_BYTES (48.0 * 1024.0 * 1024.0)
/// Bytes per byte of mesh file while Assimp imports it, when the meshes have
/// not been imported yet (the scene alone: a rough figure, 5 to 15 times what
/// OBJ and binary PLY take since issue 24's import).
#define WX_MESH_BYTES_PER_FILE_BYTE 32.0
/// Bytes per triangle of a mesh's smooth surface in the bake (model/mesh.h:
/// vertices, normals, colours, indices, materials, and the renderer's copy);
/// a mesh file holds a triangle per 16 bytes at the most.
#define WX_SMOOTH_BYTES_PER_TRIANGLE 100.0

/// With the meshes imported (info, run, bake: the check comes after the
/// import), their peak from the file and the triangles: the file (Assimp
/// reads it whole) and per triangle 400 bytes for an OBJ (Assimp's vertex per
/// face corner, the joining's tables) or 300 for the indexed formats (PLY,
/// glTF, ...: the import, then the bake's copies). Measured peaks of `run`
/// above the same scene with 10 000 triangles (docs/reliability.md): OBJ 250
/// to 450 bytes a triangle from 0.3 to 2 million triangles, PLY and glTF 120
/// to 270.
#define WX_MESH_BYTES_PER_IMPORTED_FILE_BYTE 1.0
#define WX_MESH_BYTES_PER_OBJ_TRIANGLE 400.0
#define WX_MESH_BYTES_PER_TRIANGLE 300.0
/// Bytes per texel of the bake's float framebuffer (RGBA32F x 2, R32F, depth).
#define WX_BAKE_FRAMEBUFFER_BYTES_PER_TEXEL 40.0
/// Bytes per texel of the images of one baked camera (depth 1, normal 3, impact
/// 3, dirt 3 floats; an output camera only depth and normal). One set is alive:
/// the pipeline writes a camera's files (on_maps) before the next one renders.
/// A dirt map with more channels than version 1's (three per substance, the
/// surface and area records of ageing: wx_dirt_channels) holds
/// WX_PLANE_BYTES_PER_TEXEL more per extra channel.
#define WX_BAKE_INPUT_IMAGE_BYTES_PER_TEXEL 40.0
#define WX_BAKE_OUTPUT_IMAGE_BYTES_PER_TEXEL 16.0
/// One float plane: the bytes per texel of each channel beyond version 1's.
#define WX_PLANE_BYTES_PER_TEXEL 4.0
/// Bytes per input texel in the simulation with one substance: the maps (depth,
/// normal, impact, dirt: 9 floats), the collider's depth and pyramid (5), its
/// fine test's bound (4) and its curved cells (5), the dirt texel (dirt in
/// double, its rates and its hits: 24).
#define WX_SIM_BYTES_PER_INPUT_TEXEL 74.0
/// Bytes per input texel for each substance beyond the first (docs/design.md
/// section 9): its dirt, deposit and erosion planes in the maps (3 floats) and
/// its dirt texel (24).
#define WX_SIM_BYTES_PER_SUBSTANCE_TEXEL 36.0
/// Bytes per input texel and substance of the ageing rules' baseline (the
/// amounts without the particles, in double), when the scene has rules; the
/// surface record (per-surface rules) and the area a Grow multiplies add one
/// plane each.
#define WX_SIM_BASELINE_BYTES_PER_SUBSTANCE_TEXEL 8.0
/// Bytes per texel of the dirt map being written (version 1's 5 floats; one
/// plane more per channel beyond them), plus the planes the written map and
/// the gather take from the simulation: per substance its amount and baseline,
/// and the hits (2 x substances + 1 planes). A frame of the mask's sequence
/// (<OutputMap every="k">) takes those planes of every input camera at once.
#define WX_SIM_WRITE_BYTES_PER_TEXEL 20.0
/// Bytes per particle: WX_PARTICLE_BYTES with room for the arrays to double as
/// they grow, plus the per-step events and candidates of the workers.
#define WX_BYTES_PER_PARTICLE 192.0
/// Bytes per particle for each substance beyond the first: its load in double
/// (wx_particles_slot_bytes), with the same room to grow (4 x 8).
#define WX_BYTES_PER_PARTICLE_LOAD 32.0
/// Bytes per input texel in the gather (depth, normal, and the dirt map's five
/// channels while it is read; one plane more per channel beyond them) and per
/// output texel (its depth and normal, the mask, the first pass's three planes,
/// the adaptive smoothing's eight padded planes, summed-area tables, radii,
/// changes, impacts and capped texels' noise, a bit per texel for its clean
/// texels (and at most 4 MiB for its kernels' lines), the preview's sorted values and pixels, and
/// in a run the output camera's baked depth and normal kept from the bake; the fixed second pass
/// needs less). The gather runs once per substance on the same planes; the mask
/// holds one plane more per substance beyond the first. Measured: 690 MB for a
/// 2048-px `gather` with three 2048-px input cameras, estimated 920 MB.
#define WX_GATHER_BYTES_PER_INPUT_TEXEL 36.0
#define WX_GATHER_BYTES_PER_OUTPUT_TEXEL 120.0
/// Margin over the measured sizes: allocator rounding and small buffers, and
/// the peak's variation with the threads' timing from run to run of the same
/// scene (the bunny's peak: 351, 353 and 420 MiB in three
/// runs on two cores, 3 December 2026).
#define WX_MEMORY_MARGIN 1.3

/// The longest a particle of emitter `e` can live, in seconds: never more
/// than the run; less when the forces take every particle down (gravity
/// beating any upward wind and turbulence): each of its at most maxCollisions
/// free flights then ends within the time to fall through the solver box from
/// its top at the fastest upward speed it can have (docs/reliability.md).
double wx_memory_particle_lifetime(const wx_scene *scene, const wx_emitter *e);

/// The most particles of emitter `e` alive at once: what it emits in the
/// busiest window of wx_memory_particle_lifetime, over all iterations; never
/// more than all it emits.
double wx_memory_particles_alive(const wx_scene *scene, const wx_emitter *e);

/// Estimates the peak memory of running `phases` (WX_PHASE_*) of the scene: the
/// bake counts when `phases` has it and some camera is baked, the particles when
/// it has the simulation.
void wx_memory_estimate(const wx_scene *scene, unsigned phases, wx_memory_need *need);

/// wx_memory_estimate with the meshes imported (`geometry`, in scene order;
/// NULL: the scene alone), whose triangles bound the import's memory better
/// than their files' sizes.
void wx_memory_estimate_geometry(const wx_scene *scene, unsigned phases,
                                 const wx_geometry *geometry, wx_memory_need *need);

/// Bytes this process can still use: the least of MemAvailable, the cgroup's
/// memory.max minus memory.current and RLIMIT_AS / RLIMIT_DATA; < 0 when
/// unknown. $WX_MEMORY_AVAILABLE_MB overrides it (tests, or to insist).
double wx_memory_available(void);

/// Refuses (WX_BAD_INPUT, "scene:LINE: ...") a run whose estimate exceeds the
/// memory available, naming the numbers, before any work starts.
wx_result wx_memory_check(const wx_scene *scene, unsigned phases, const wx_geometry *geometry,
                          wx_error *err);

#endif
