// point_rules.c: the ageing rules that act on each surface point alone
// (docs/design.md section 9): Transfer, Decay and Grow on one texel's amounts
// and baseline. Both ways of ageing run them: texel by texel (ageing.c) and
// rule by rule over the whole surface with the automata (surface_automata.c).
#include "sim/solver_internal.h"

// Runs `rules` on one texel's amounts a[] (and its baseline b[], may be NULL),
// in order, each seeing the result of the one before (docs/design.md section 9);
// `area` is the surface the texel grows on. Seed and Spread are skipped.
void sim_run_rules(const wx_rule *rules, int count, double *a, double *b, double area,
                   wx_substance_ledger *ledger)
{
    for (int k = 0; k < count; ++k) {
        const wx_rule *r = &rules[k];
        int s = r->substance;
        switch (r->kind) {
        case WX_RULE_TRANSFER: {
            double t = (double)r->rate * a[s];
            a[s] -= t;
            a[r->to] += t;
            ledger[s].transferred_out += t;
            ledger[r->to].transferred_in += t;
            if (b != NULL) {
                double tb = (double)r->rate * b[s];
                b[s] -= tb;
                b[r->to] += tb;
            }
            break;
        }
        case WX_RULE_DECAY: {
            double d = (double)r->rate * a[s];
            a[s] -= d;
            ledger[s].decayed += d;
            if (b != NULL) {
                b[s] -= (double)r->rate * b[s];
            }
            break;
        }
        case WX_RULE_GROW: {
            double g = (double)r->amount * area;
            a[s] += g;
            ledger[s].grown += g;
            if (b != NULL) {
                b[s] += g;
            }
            break;
        }
        case WX_RULE_SEED:
        case WX_RULE_SPREAD:
        case WX_RULE_CRACK:
        case WX_RULE_PEEL:
            break; // surface_automata.c runs them over the whole surface
        }
    }
}
