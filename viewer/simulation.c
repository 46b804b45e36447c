// simulation.c: the simulation the viewer steps (app.h): steps per frame in
// real time or fixed with --frames, starting again, and G's gather.
#include "app.h"

#include <inttypes.h>

#include "sim/simulate.h"

static const double STEP_BUDGET_S = 0.025; ///< wall-clock stepping per frame, at most

void vw_app_reset_rates(vw_app *a)
{
    a->rate_t0 = glfwGetTime();
    a->rate_steps = 0;
    a->rate_frames = 0;
    a->step_debt = 0.0;
}

// One step, unless the simulation has run the scene's steps.
bool vw_app_step_once(vw_app *a)
{
    wx_error err;
    if (vw_world_finished(a->world)) {
        return false;
    }
    if (wx_sim_step(a->world->sim, &err) != WX_OK) {
        a->playing = false;
        vw_app_report(a, true, "simulation stopped: %s", err.message);
        return false;
    }
    a->rate_steps++;
    a->timing.steps++;
    return true;
}

bool vw_app_restart(vw_app *a)
{
    wx_error err;
    if (vw_world_restart(a->world, &a->settings, &err) != WX_OK) {
        vw_app_report(a, true, "cannot start again: %s", err.message);
        return false;
    }
    vw_app_reset_rates(a);
    a->playing = true;
    return true;
}

// Steps the simulation for this frame: a fixed count with --frames, else what
// real time asks for at the chosen speed, within STEP_BUDGET_S.
void vw_app_advance(vw_app *a, double now)
{
    double wall_dt = now - a->last_frame_s;
    a->last_frame_s = now;
    if (!a->playing) {
        a->step_debt = 0.0;
        return;
    }
    if (a->frames > 0) {
        for (int k = 0; k < a->steps_per_frame && vw_app_step_once(a); ++k) {
        }
    } else {
        wall_dt = wall_dt < 0.25 ? wall_dt : 0.25;
        a->step_debt += wall_dt * a->speed / a->world->scene.time_step;
        double deadline = now + STEP_BUDGET_S;
        while (a->step_debt >= 1.0 && vw_app_step_once(a)) {
            a->step_debt -= 1.0;
            if (glfwGetTime() > deadline) {
                break;
            }
        }
        // What did not fit in the budget is dropped: slower than real time, but
        // the window stays responsive.
        a->step_debt = a->step_debt < 1.0 ? a->step_debt : 1.0;
    }
    if (a->playing && vw_world_finished(a->world)) {
        a->playing = false;
        vw_app_report(a, false,
                      "simulation finished after %" PRId64 " steps; G saves the mask, space starts "
                      "again",
                      wx_sim_step_count(a->world->sim));
    }
}

wx_result vw_app_gather(vw_app *a)
{
    if (a->window != NULL) {
        glfwSetWindowTitle(a->window, "weathering-viewer: gathering ...");
    }
    char saved[WX_PATH_MAX];
    wx_error err;
    double t0 = glfwGetTime();
    wx_result r = vw_world_gather(a->world, saved, &err);
    if (r != WX_OK) {
        vw_app_report(a, true, "gather failed: %s", err.message);
        return r;
    }
    double t = glfwGetTime() - t0;
    if (a->world->scene.output_index < 0) {
        vw_app_report(a, false,
                      "saved the dirt maps in %s (no output camera, so no mask) at t = %.3f s",
                      saved, wx_sim_time(a->world->sim));
    } else {
        vw_app_report(a, false, "saved the mask %s at t = %.3f s (%.1f s)", saved,
                      wx_sim_time(a->world->sim), t);
    }
    return WX_OK;
}
