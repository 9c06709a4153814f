/* Dahlquist3: an FMI 3.0 co-simulation FMU written for navfmu's tests.
 *
 * x' = -k (x - u), x(start) = x0, stepped exactly over each communication step with u held:
 *     x(t + h) = u + (x(t) - u) exp(-k h)
 * so a test knows every value a master must produce.  Besides: count_out = count_in + steps
 * (Int32), steps = number of steps done + offset (Int64), flag_out = !flag (Boolean), a
 * String parameter label, and stop_at > 0 asks the master to end the simulation
 * (terminateSimulation) at the first communication point at or after stop_at; abort_at > 0
 * aborts the process there (an FMU that crashes its host). */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define MODEL_TOKEN "{8c4e0a37-3d0b-4c59-9b7e-5f1d2a6c3e01}"

struct Model {
    double x, k, x0, u, stop_at, abort_at;
    int32_t count_in;
    int64_t steps, offset;
    bool flag;
    char label[64];
};

enum { VR_TIME, VR_X, VR_K, VR_X0, VR_U, VR_COUNT_IN, VR_COUNT_OUT, VR_STEPS, VR_OFFSET,
       VR_FLAG, VR_FLAG_OUT, VR_LABEL, VR_STOP_AT, VR_ABORT_AT };

static void model_reset(struct Model *m)
{
    memset(m, 0, sizeof *m);
    m->k = 1.0;
    m->x0 = 1.0;
    m->x = 1.0;
    strcpy(m->label, "dahlquist");
}

static int model_get(const struct Model *m, unsigned vr, int kind, void *value);
static int model_set(struct Model *m, unsigned vr, int kind, const void *value, int initializing);
static int model_step(struct Model *m, double t, double h, bool *terminate, char *message,
                      size_t size);

#include "fmi3_shell.h"

static int model_get(const struct Model *m, unsigned vr, int kind, void *value)
{
    switch (kind) {
    case K_F64: {
        double *v = value;
        switch (vr) {
        case VR_X: *v = m->x; return 0;
        case VR_K: *v = m->k; return 0;
        case VR_X0: *v = m->x0; return 0;
        case VR_U: *v = m->u; return 0;
        case VR_STOP_AT: *v = m->stop_at; return 0;
        case VR_ABORT_AT: *v = m->abort_at; return 0;
        default: return -1;
        }
    }
    case K_I32:
        if (vr == VR_COUNT_IN) { *(int32_t *)value = m->count_in; return 0; }
        if (vr == VR_COUNT_OUT) { *(int32_t *)value = (int32_t)(m->count_in + m->steps); return 0; }
        return -1;
    case K_I64:
        if (vr == VR_STEPS) { *(int64_t *)value = m->steps + m->offset; return 0; }
        if (vr == VR_OFFSET) { *(int64_t *)value = m->offset; return 0; }
        return -1;
    case K_BOOL:
        if (vr == VR_FLAG) { *(bool *)value = m->flag; return 0; }
        if (vr == VR_FLAG_OUT) { *(bool *)value = !m->flag; return 0; }
        return -1;
    case K_STR:
        if (vr == VR_LABEL) { *(const char **)value = m->label; return 0; }
        return -1;
    default:
        return -1;
    }
}

static int model_set(struct Model *m, unsigned vr, int kind, const void *value, int initializing)
{
    if (kind == K_F64 && vr == VR_U) { m->u = *(const double *)value; return 0; }
    if (kind == K_I32 && vr == VR_COUNT_IN) { m->count_in = *(const int32_t *)value; return 0; }
    if (kind == K_BOOL && vr == VR_FLAG) { m->flag = *(const bool *)value; return 0; }
    if (!initializing) return -1;
    if (kind == K_F64 && vr == VR_K) { m->k = *(const double *)value; return 0; }
    if (kind == K_F64 && vr == VR_X0) { m->x0 = m->x = *(const double *)value; return 0; }
    if (kind == K_F64 && vr == VR_STOP_AT) { m->stop_at = *(const double *)value; return 0; }
    if (kind == K_F64 && vr == VR_ABORT_AT) { m->abort_at = *(const double *)value; return 0; }
    if (kind == K_I64 && vr == VR_OFFSET) { m->offset = *(const int64_t *)value; return 0; }
    if (kind == K_STR && vr == VR_LABEL) {
        const char *text = *(const char *const *)value;
        if (strlen(text) >= sizeof m->label) return -1;
        strcpy(m->label, text);
        return 0;
    }
    return -1;
}

static int model_step(struct Model *m, double t, double h, bool *terminate, char *message,
                      size_t size)
{
    if (!(h > 0.0)) {
        snprintf(message, size, "%s: step size %g is not positive", m->label, h);
        return -1;
    }
    if (m->abort_at > 0.0 && t + h >= m->abort_at - 1e-9 * h) abort();   /* a crashing FMU */
    m->x = m->u + (m->x - m->u) * exp(-m->k * h);
    m->steps += 1;
    if (m->stop_at > 0.0 && t + h >= m->stop_at - 1e-9 * h) {
        *terminate = true;
        snprintf(message, size, "%s: stop_at = %g s reached", m->label, m->stop_at);
    }
    return 0;
}
