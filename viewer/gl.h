// gl.h: how the viewer includes OpenGL (3.3 core through GLFW and the system's
// libGL, never OSMesa), and a shader-program helper.
#ifndef VW_GL_H
#define VW_GL_H

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>

#include "core/error.h"

/// Compiles and links a vertex and a fragment shader (GLSL source strings).
/// `name` labels the compiler log in the error message.
wx_result vw_gl_program(const char *name, const char *vertex_src, const char *fragment_src,
                        GLuint *program, wx_error *err);

#endif
