// limits.h: the sizes the program refuses to go beyond, in one place, so that
// every module checks the same numbers (docs/reliability.md lists them).
#ifndef WX_LIMITS_H
#define WX_LIMITS_H

/// Longest path the program handles (a longer --out or scene path is refused).
#define WX_PATH_MAX 4096

/// Largest map side, reading and writing (<View resolution>, EXR files).
#define WX_MAP_MAX_SIDE 16384
/// Largest number of texels in one map: 16384 x 16384 (1 GiB per float channel).
#define WX_MAP_MAX_TEXELS (16384LL * 16384LL)

/// Most input cameras a scene may have (the collider numbers them in a byte).
#define WX_MAX_INPUT_CAMERAS 64

/// Most substances a scene may declare (docs/design.md section 9), and the
/// longest substance name.
#define WX_MAX_SUBSTANCES 8
#define WX_SUBSTANCE_NAME_MAX 32

/// Most layers a camera records (<Ortho layers>, docs/design.md section 14).
#define WX_MAX_LAYERS 8

/// Channels and header attributes of an image: a dirt map of 8 substances holds
/// 4 channels per substance and the surface record (40), once per layer.
#define WX_IMAGE_MAX_CHANNELS (40 * WX_MAX_LAYERS)
#define WX_IMAGE_MAX_ATTRS 16
/// Longest channel or attribute name, and string attribute.
#define WX_NAME_MAX 64
#define WX_ATTR_STRING_MAX 1024

/// Size of the buffers that hold a plain file name the program writes into an
/// output folder (a name of up to 255 characters and a suffix).
#define WX_OUTPUT_NAME_MAX 320

/// Longest file name a folder holds (NAME_MAX of Linux's file systems).
#define WX_FILE_NAME_MAX 255
/// Longest name of a file a run writes: its temporary ".NAME.tmpPID"
/// (core/atomic_file.c) adds 5 characters and the pid's, at most 7 (Linux's
/// pid_max is at most 2^22), and must fit WX_FILE_NAME_MAX too.
#define WX_OUTPUT_FILE_NAME_MAX (WX_FILE_NAME_MAX - 5 - 7)
/// What a temporary's name adds to its file's: "." and ".tmp" and the pid.
#define WX_TEMP_NAME_EXTRA 12

/// Largest amount per square metre (and per texel) the scene's amounts may put
/// on one texel in the worst case (docs/reliability.md): maps and masks hold
/// floats, and a sum over a whole map (2^28 texels) of values up to this stays
/// below FLT_MAX (3.4e38).
#define WX_AMOUNT_MAX 1e30

/// Longest material name kept from a mesh file.
#define WX_MATERIAL_NAME_MAX 128
/// Most distinct material names one mesh file may use (per-triangle index is 16 bits).
#define WX_MESH_MAX_MATERIALS 65535

#endif
