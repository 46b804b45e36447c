// window.c: the viewer's window (app.h): GLFW's OpenGL 3.3 core window and
// its input callbacks.
#include "app.h"

#include <stdio.h>

static char glfw_message[512];

static void on_glfw_error(int code, const char *description)
{
    snprintf(glfw_message, sizeof glfw_message, "%s (GLFW error 0x%x)", description, code);
}

int vw_app_open_window(vw_app *a)
{
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit()) {
        fprintf(stderr,
                "weathering-viewer: cannot open a window: %s; is there a display? (tests run "
                "under `xvfb-run -a`)\n",
                glfw_message);
        return WX_FAIL;
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_DEPTH_BITS, 24);
    glfwWindowHint(GLFW_SAMPLES, 0);
    if (a->frames > 0) {
        glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
    }
    a->window = glfwCreateWindow(a->width, a->height, "weathering-viewer", NULL, NULL);
    if (a->window == NULL) {
        fprintf(stderr, "weathering-viewer: cannot create an OpenGL 3.3 core window: %s\n",
                glfw_message);
        return WX_FAIL;
    }
    glfwMakeContextCurrent(a->window);
    glfwSwapInterval(a->frames > 0 ? 0 : 1);
    glfwSetWindowUserPointer(a->window, a);
    glfwSetKeyCallback(a->window, vw_app_on_key);
    glfwSetMouseButtonCallback(a->window, vw_app_on_mouse_button);
    glfwSetCursorPosCallback(a->window, vw_app_on_cursor);
    glfwSetScrollCallback(a->window, vw_app_on_scroll);
    if (a->verbose) {
        fprintf(stderr, "weathering-viewer: %s, %s\n", (const char *)glGetString(GL_RENDERER),
                (const char *)glGetString(GL_VERSION));
    }
    return -1;
}
