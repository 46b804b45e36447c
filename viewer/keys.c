// keys.c: the viewer's input (app.h): the keys (docs/viewer.md), the mouse's
// orbit, pan and zoom, and the mask M asked for, computed after the frame that
// says so.
#include "app.h"

#include "core/progress.h"

static const double MIN_SPEED = 1.0 / 16.0, MAX_SPEED = 256.0;

// Computes the mask M asked for (after the frame that said so) and shows it.
void vw_app_compute_requested_mask(vw_app *a)
{
    int m = a->mask_request;
    a->mask_request = -1;
    if (m < 0 || m >= vw_world_mask_count(a->world)) {
        return;
    }
    wx_error err;
    double t0 = wx_now_s();
    if (vw_world_show_mask(a->world, m, &err) != WX_OK) {
        vw_app_report(a, true, "mask %s: %s", a->world->scene.masks[m].name, err.message);
        return;
    }
    vw_app_report_mask(a, wx_now_s() - t0);
    a->last_frame_s = glfwGetTime(); // the time it took is not owed to the simulation
    a->step_debt = 0.0;
}

static void toggle_camera(vw_app *a, int c)
{
    if (c >= a->world->scene.camera_count) {
        return;
    }
    a->camera_visible[c] = !a->camera_visible[c];
    const wx_scene_camera *cam = &a->world->scene.cameras[c];
    vw_app_report(a, false, "camera %d '%s' %s", c + 1, cam->name,
                  a->camera_visible[c] ? "on" : "off");
}

// L: the next layer shown (every layer's samples, then each layer's alone).
static void next_layer(vw_app *a)
{
    const vw_world *w = a->world;
    if (w->max_layers <= 1) {
        vw_app_report(a, false,
                      "every camera has one layer: nothing to cycle (layers=\"K\" on an "
                      "<Ortho> bakes more)");
        return;
    }
    a->show.layer = vw_world_next_layer(w, a->show.layer);
    if (a->show.layer < 0) {
        vw_app_report(a, false, "depth samples and hits of all %d layers (deeper ones darker)",
                      w->max_layers);
        return;
    }
    int samples = 0, cameras = 0;
    for (int c = 0; c < w->scene.camera_count; ++c) {
        samples += vw_world_layer_points(w, c, a->show.layer).count;
        cameras += a->show.layer < vw_world_camera_layers(w, c);
    }
    vw_app_report(a, false, "layer %d of 0-%d only: %d depth samples of %d camera%s%s",
                  a->show.layer, w->max_layers - 1, samples, cameras, cameras == 1 ? "" : "s",
                  a->show.layer == 0 ? " (the first surface each ray meets)" : "");
}

static void next_substance(vw_app *a)
{
    vw_world *w = a->world;
    int count = vw_world_substance_count(w);
    if (count == 1) {
        vw_app_report(a, false, "the scene has one substance, %s", vw_world_substance_name(w));
        return;
    }
    vw_world_next_substance(w);
    vw_app_report(a, false,
                  "showing substance %d/%d, %s: on particles (full colour at load %g) and deposits",
                  w->substance + 1, count, vw_world_substance_name(w), (double)w->load_scale);
}

// M: the next derived mask on the depth samples (off after the last); one not
// computed yet is computed after the next frame, which says so.
static void next_mask(vw_app *a)
{
    vw_world *w = a->world;
    if (vw_world_mask_count(w) == 0) {
        vw_app_report(a, false, "the scene has no <Masks>");
        return;
    }
    int m = vw_world_next_mask(w);
    if (!vw_world_mask_ready(w, m)) {
        a->mask_request = m;
        vw_app_report_computing(a, "", m);
        return;
    }
    wx_error err;
    if (vw_world_show_mask(w, m, &err) != WX_OK) { // known: nothing to compute
        vw_app_report(a, true, "%s", err.message);
        return;
    }
    vw_app_report_mask(a, -1.0);
}

void vw_app_on_key(GLFWwindow *window, int key, int scancode, int action, int mods)
{
    (void)scancode;
    (void)mods;
    vw_app *a = glfwGetWindowUserPointer(window);
    if (action != GLFW_PRESS && !(action == GLFW_REPEAT && key == GLFW_KEY_N)) {
        return;
    }
    switch (key) {
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q: glfwSetWindowShouldClose(window, GLFW_TRUE); break;
    case GLFW_KEY_SPACE:
        if (vw_world_finished(a->world)) {
            vw_app_restart(a);
        } else {
            a->playing = !a->playing;
        }
        vw_app_update_title(a);
        break;
    case GLFW_KEY_N:
        a->playing = false;
        vw_app_step_once(a);
        vw_app_update_title(a);
        break;
    case GLFW_KEY_R: vw_app_reload(a); break;
    case GLFW_KEY_G: vw_app_gather(a); break; // reported in the overlay either way
    case GLFW_KEY_H:
        a->show.hits = !a->show.hits;
        vw_app_report(a, false, "hit points %s", a->show.hits ? "on" : "off");
        break;
    case GLFW_KEY_D:
        a->show.depth_samples = !a->show.depth_samples;
        vw_app_report(a, false, "depth samples %s", a->show.depth_samples ? "on" : "off");
        break;
    case GLFW_KEY_P:
        a->show.particles = !a->show.particles;
        vw_app_report(a, false, "particles %s", a->show.particles ? "on" : "off");
        break;
    case GLFW_KEY_S: next_substance(a); break;
    case GLFW_KEY_L: next_layer(a); break;
    case GLFW_KEY_M:
        if (a->mask_request < 0) {
            next_mask(a);
        }
        break;
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_KP_ADD:
        a->speed = a->speed * 2.0 < MAX_SPEED ? a->speed * 2.0 : MAX_SPEED;
        vw_app_report(a, false, "speed x%g (simulated seconds per second)", a->speed);
        break;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT:
        a->speed = a->speed * 0.5 > MIN_SPEED ? a->speed * 0.5 : MIN_SPEED;
        vw_app_report(a, false, "speed x%g (simulated seconds per second)", a->speed);
        break;
    case GLFW_KEY_BACKSPACE:
        if (vw_app_restart(a)) {
            vw_app_report(a, false, "started again");
        }
        break;
    case GLFW_KEY_HOME: {
        int w = 1, h = 1;
        glfwGetFramebufferSize(window, &w, &h);
        vw_orbit_frame(&a->orbit, a->world->frame_lo, a->world->frame_hi,
                       (float)w / (float)(h > 0 ? h : 1));
        break;
    }
    case GLFW_KEY_F1:
        a->help = !a->help;
        if (a->help) {
            vw_app_print_key_help();
        }
        break;
    default:
        if (key >= GLFW_KEY_1 && key <= GLFW_KEY_9) {
            toggle_camera(a, key - GLFW_KEY_1);
        } else if (key >= GLFW_KEY_KP_1 && key <= GLFW_KEY_KP_9) {
            toggle_camera(a, key - GLFW_KEY_KP_1);
        }
        break;
    }
}

void vw_app_on_mouse_button(GLFWwindow *window, int button, int action, int mods)
{
    (void)mods;
    vw_app *a = glfwGetWindowUserPointer(window);
    bool down = action == GLFW_PRESS;
    if (button == GLFW_MOUSE_BUTTON_LEFT) {
        a->rotating = down;
    } else if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE) {
        a->panning = down;
    }
    glfwGetCursorPos(window, &a->cursor_x, &a->cursor_y);
}

void vw_app_on_cursor(GLFWwindow *window, double x, double y)
{
    vw_app *a = glfwGetWindowUserPointer(window);
    float dx = (float)(x - a->cursor_x), dy = (float)(y - a->cursor_y);
    a->cursor_x = x;
    a->cursor_y = y;
    if (a->rotating) {
        vw_orbit_rotate(&a->orbit, dx, dy);
    } else if (a->panning) {
        int w = 1, h = 1;
        glfwGetWindowSize(window, &w, &h);
        vw_orbit_pan(&a->orbit, dx, dy, (float)h);
    }
}

void vw_app_on_scroll(GLFWwindow *window, double dx, double dy)
{
    (void)dx;
    vw_app *a = glfwGetWindowUserPointer(window);
    vw_orbit_zoom(&a->orbit, (float)dy);
}
