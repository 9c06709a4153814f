/* Passthrough3: an FMI 3.0 co-simulation FMU written for navfmu's tests.  Float64 inputs
 * with value references 1 .. 64 and outputs with value references 1001 .. 1064: output
 * 1000 + i is input i at every moment (direct feedthrough; which of them exist, with their
 * names and units, the model description says). */
#include <stdbool.h>
#include <string.h>

#define MODEL_TOKEN "{8c4e0a37-3d0b-4c59-9b7e-5f1d2a6c3e02}"
#define CHANNELS 64

struct Model {
    double u[CHANNELS];
};

static void model_reset(struct Model *m) { memset(m, 0, sizeof *m); }

static int model_get(const struct Model *m, unsigned vr, int kind, void *value);
static int model_set(struct Model *m, unsigned vr, int kind, const void *value, int initializing);
static int model_step(struct Model *m, double t, double h, bool *terminate, char *message,
                      size_t size);

#include "fmi3_shell.h"

static int channel(unsigned vr)
{
    if (vr >= 1 && vr <= CHANNELS) return (int)vr - 1;
    if (vr >= 1001 && vr <= 1000 + CHANNELS) return (int)vr - 1001;
    return -1;
}

static int model_get(const struct Model *m, unsigned vr, int kind, void *value)
{
    int i = channel(vr);
    if (kind != K_F64 || i < 0) return -1;
    *(double *)value = m->u[i];
    return 0;
}

static int model_set(struct Model *m, unsigned vr, int kind, const void *value, int initializing)
{
    (void)initializing;
    if (kind != K_F64 || vr < 1 || vr > CHANNELS) return -1;
    m->u[vr - 1] = *(const double *)value;
    return 0;
}

static int model_step(struct Model *m, double t, double h, bool *terminate, char *message,
                      size_t size)
{
    (void)m; (void)t; (void)h; (void)terminate; (void)message; (void)size;
    return 0;
}
