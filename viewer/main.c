// main.c: weathering-viewer, the live view of a simulation (thesis 4.8.5,
// docs/design.md sections 1 and 6; docs/viewer.md is the user's guide).
//
//   weathering-viewer SCENE.xml [--out DIR] [--threads N] [--size WxH]
//                     [--screenshot FILE.png] [--frames N] [--steps-per-frame K]
//                     [--substance NAME] [--mask NAME] [-v]
//
// The scene is read (and baked, by `weathering bake` in a child process) before
// any window opens, so bad input is reported with exit status 2 even without a
// display. The simulation is the library's, stepped at the scene's fixed time
// step: interactively as many steps per frame as real time asks for, within a
// time budget so the window stays responsive; with --frames, a fixed number per
// frame so that a screenshot is reproducible.
//
// This file holds the frame loop; app.h the program's state and its other
// parts: the command line (args.c), the worlds (reload.c), the simulation
// (simulation.c), the keys and mouse (keys.c), the window (window.c) and the
// messages (messages.c).
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>

#include "app.h"
#include "screenshot.h"

// --- the frame loop -------------------------------------------------------------------------

static void update_rates(vw_app *a, double now)
{
    a->rate_frames++;
    double elapsed = now - a->rate_t0;
    if (elapsed >= 0.5) {
        a->steps_per_s = (double)a->rate_steps / elapsed;
        a->frames_per_s = (double)a->rate_frames / elapsed;
        a->rate_t0 = now;
        a->rate_steps = 0;
        a->rate_frames = 0;
    }
    if (now - a->title_s >= 0.25) {
        a->title_s = now;
        vw_app_update_title(a);
    }
}

static void print_timing(const vw_app *a)
{
    const vw_timing *t = &a->timing;
    if (t->frames == 0) {
        return;
    }
    double f = (double)t->frames;
    fprintf(stderr,
            "weathering-viewer: %d frames in %.3f s: %.1f fps; per frame %.2f ms simulating "
            "(%.2f steps), %.2f ms uploading, %.2f ms drawing and swapping; %" PRId64
            " live particles at most; on average %.0f particles and %.0f depth samples drawn "
            "(the nearest in each pixel)\n",
            t->frames, t->total_s, f / t->total_s, 1e3 * t->sim_s / f, (double)t->steps / f,
            1e3 * t->upload_s / f, 1e3 * t->draw_s / f, t->max_particles,
            (double)t->drawn_particles / f, (double)t->drawn_samples / f);
}

static int run(vw_app *a)
{
    wx_error err;
    int fb_w = 1, fb_h = 1;
    glfwGetFramebufferSize(a->window, &fb_w, &fb_h);
    vw_orbit_frame(&a->orbit, a->world->frame_lo, a->world->frame_hi,
                   (float)fb_w / (float)(fb_h > 0 ? fb_h : 1));
    a->last_frame_s = glfwGetTime();
    vw_app_reset_rates(a);
    double start = glfwGetTime();
    for (int frame = 0; !glfwWindowShouldClose(a->window); ++frame) {
        if (a->frames == 0 && !a->playing && a->pending == NULL) {
            glfwWaitEventsTimeout(0.25); // nothing moves: redraw on input only
        } else {
            glfwPollEvents();
        }
        vw_app_poll_pending(a);
        double t0 = glfwGetTime();
        vw_app_advance(a, t0);
        double t1 = glfwGetTime();
        glfwGetFramebufferSize(a->window, &fb_w, &fb_h);
        float mvp[16];
        vw_orbit_matrix(&a->orbit, (float)fb_w / (float)(fb_h > 0 ? fb_h : 1), mvp);
        if (vw_draw_update(&a->draw, a->world, &a->show, mvp, fb_w, fb_h, &err) != WX_OK) {
            fprintf(stderr, "weathering-viewer: %s\n", err.message);
            return WX_FAIL;
        }
        double t2 = glfwGetTime();
        glViewport(0, 0, fb_w, fb_h);
        vw_draw_frame(&a->draw, a->world, &a->show, mvp);
        vw_app_draw_overlay(a, fb_w, fb_h);
        bool last = a->frames > 0 && frame + 1 >= a->frames;
        if (last && a->screenshot != NULL) {
            if (vw_screenshot_write(a->screenshot, fb_w, fb_h, &err) != WX_OK) {
                fprintf(stderr, "weathering-viewer: %s\n", err.message);
                return WX_FAIL;
            }
            printf("weathering-viewer: wrote %s (%dx%d)\n", a->screenshot, fb_w, fb_h);
        }
        glfwSwapBuffers(a->window);
        double t3 = glfwGetTime();
        wx_particle_view view;
        wx_sim_particles(a->world->sim, &view);
        a->timing.frames++;
        a->timing.sim_s += t1 - t0;
        a->timing.upload_s += t2 - t1;
        a->timing.draw_s += t3 - t2;
        a->timing.max_particles =
            view.count > a->timing.max_particles ? view.count : a->timing.max_particles;
        a->timing.drawn_particles += a->draw.particle_count;
        a->timing.drawn_samples += a->show.depth_samples ? a->draw.depth_count : 0;
        update_rates(a, t3);
        if (last) {
            break;
        }
        if (a->mask_request >= 0) {
            vw_app_compute_requested_mask(a); // the frame just shown says it is coming
        }
    }
    a->timing.total_s = glfwGetTime() - start;
    if (a->gather_at_end) {
        wx_result r = vw_app_gather(a);
        if (r != WX_OK) {
            return r;
        }
    }
    GLenum gl_err = glGetError();
    if (gl_err != GL_NO_ERROR) {
        fprintf(stderr, "weathering-viewer: GL error 0x%x\n", gl_err);
        return WX_FAIL;
    }
    return 0;
}

int main(int argc, char **argv)
{
    static vw_app a; // large; zero-initialised
    a.speed = 1.0;
    a.mask_request = -1;
    a.show.layer = -1;
    a.show.depth_samples = true;
    a.show.particles = true;
    a.show.hits = true;
    int status = vw_app_parse_args(argc, argv, &a);
    if (status >= 0) {
        return status;
    }
    if (!vw_executable_dir(argv[0], a.exe_dir)) {
        snprintf(a.exe_dir, sizeof a.exe_dir, ".");
    }
    status = vw_app_load_first_world(&a);
    if (status < 0) {
        status = vw_app_open_window(&a);
    }
    if (status < 0) {
        wx_error err;
        wx_result r = vw_draw_init(&a.draw, HIT_CAPACITY, &err);
        if (r == WX_OK) {
            r = vw_overlay_init(&a.overlay, &err);
        }
        if (r != WX_OK) {
            fprintf(stderr, "weathering-viewer: %s\n", err.message);
            status = r;
        } else if (!vw_app_reset_camera_visibility(&a)) {
            fprintf(stderr, "weathering-viewer: out of memory\n");
            status = WX_FAIL;
        } else if (vw_draw_set_world(&a.draw, a.world, &err) != WX_OK) {
            fprintf(stderr, "weathering-viewer: %s\n", err.message);
            status = WX_FAIL;
        }
    }
    if (status < 0) {
        a.playing = true;
        if (a.frames == 0) {
            printf("weathering-viewer: %s; press F1 in the window for help\n",
                   a.world->scene.path);
            fflush(stdout);
        }
        status = run(&a);
        if (a.verbose) {
            print_timing(&a);
        }
    }
    vw_app_cancel_pending(&a);
    if (a.window != NULL) {
        vw_overlay_free(&a.overlay);
        vw_draw_free(&a.draw);
        glfwDestroyWindow(a.window);
    }
    glfwTerminate();
    if (a.world != NULL) {
        vw_world_free(a.world);
        free(a.world);
    }
    free(a.camera_visible);
    return status;
}
