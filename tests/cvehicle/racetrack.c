/* A small FMI 2.0 co-simulation vehicle that navfmu did not build: a car on a flat racetrack
 * (two straights joined by two half circles) at constant speed, truth outputs only.
 *
 * Track: centre at the origin (lat0, lon0, h0), straights of length 2 L along north, the
 * half circles of radius R at north = +-L; the car starts at the east end of the southern
 * half circle ... see track(): the distance s = V t along the track gives the position, the
 * NED velocity (speed V along the heading) and the attitude (level, yaw = heading).
 * Geodetic position from the local plane with the WGS-84 radii at lat0 (the track is a few
 * hundred metres: the radii change by 1e-7 across it).  Outputs are the state at the end of
 * each step, truth_time = that time. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define N_REALS 13
enum { V_TIME, V_LAT, V_LON, V_H, V_VN, V_VE, V_VD, V_ROLL, V_PITCH, V_YAW,
       P_SPEED, P_RADIUS, P_HALF_STRAIGHT };

static const double LAT0 = 0.6998770300497261, LON0 = 2.069960492865275, H0 = 100.0;

typedef struct {
    double r[N_REALS];
    double time;
    fmi2CallbackFunctions cb;
    char name[64];
} Car;

static void track(Car *c, double t)
{
    const double V = c->r[P_SPEED], R = c->r[P_RADIUS], L = c->r[P_HALF_STRAIGHT];
    const double lap = 4.0 * L + 2.0 * M_PI * R;
    double s = fmod(V * t, lap), n, e, psi;
    if (s < 2.0 * L) {                       /* eastern straight, northbound */
        n = -L + s; e = R; psi = 0.0;
    } else if ((s -= 2.0 * L) < M_PI * R) {  /* northern half circle, turning left */
        double a = s / R;
        n = L + R * sin(a); e = R * cos(a); psi = -a;
    } else if ((s -= M_PI * R) < 2.0 * L) {  /* western straight, southbound */
        n = L - s; e = -R; psi = -M_PI;
    } else {                                 /* southern half circle */
        double a = (s - 2.0 * L) / R;
        n = -L - R * sin(a); e = -R * cos(a); psi = -M_PI - a;
    }
    const double a_wgs = 6378137.0, e2 = 6.69437999014e-3, sl = sin(LAT0);
    const double w = 1.0 - e2 * sl * sl, re = a_wgs / sqrt(w), rn = re * (1.0 - e2) / w;
    c->r[V_TIME] = t;
    c->r[V_LAT] = LAT0 + n / (rn + H0);
    c->r[V_LON] = LON0 + e / ((re + H0) * cos(LAT0));
    c->r[V_H] = H0;
    c->r[V_VN] = V * cos(psi);
    c->r[V_VE] = V * sin(psi);
    c->r[V_VD] = 0.0;
    c->r[V_ROLL] = 0.0;
    c->r[V_PITCH] = 0.0;
    c->r[V_YAW] = atan2(sin(psi), cos(psi));
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[])
{ (void)c; (void)on; (void)n; (void)cat; return fmi2OK; }

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String res,
                              const fmi2CallbackFunctions *cb, fmi2Boolean vis, fmi2Boolean log)
{
    (void)guid; (void)res; (void)vis; (void)log;
    if (type != fmi2CoSimulation) return NULL;
    Car *c = calloc(1, sizeof(Car));
    if (!c) return NULL;
    c->cb = *cb;
    snprintf(c->name, sizeof c->name, "%s", name ? name : "car");
    c->r[P_SPEED] = 20.0; c->r[P_RADIUS] = 100.0; c->r[P_HALF_STRAIGHT] = 200.0;
    track(c, 0.0);
    return c;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tol_on, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stop_on, fmi2Real stop)
{
    (void)tol_on; (void)tol; (void)stop_on; (void)stop;
    ((Car *)c)->time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{ Car *car = c; track(car, car->time); return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{ Car *car = c; track(car, car->time); return fmi2OK; }
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) { Car *car = c; car->time = 0.0; track(car, 0.0); return fmi2OK; }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[])
{
    Car *car = c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= N_REALS) return fmi2Error;
        v[i] = car->r[vr[i]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[])
{
    Car *car = c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] < P_SPEED || vr[i] >= N_REALS || !(v[i] > 0.0)) return fmi2Error;
        car->r[vr[i]] = v[i];
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[])
{ (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[])
{ (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[])
{ (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[])
{ (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[])
{ (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[])
{ (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_prior)
{
    (void)no_prior;
    Car *car = c;
    if (!(h > 0.0)) return fmi2Error;
    car->time = t + h;
    track(car, car->time);
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return fmi2Error; }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *v)
{ (void)c; (void)s; (void)v; return fmi2Discard; }
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *v)
{ (void)c; (void)s; (void)v; return fmi2Discard; }
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *v)
{ (void)c; (void)s; (void)v; return fmi2Discard; }
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v)
{ (void)c; (void)s; (void)v; return fmi2Discard; }
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *v)
{ (void)c; (void)s; (void)v; return fmi2Discard; }
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n)
{ (void)c; (void)s; (void)n; return fmi2Error; }
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n)
{ (void)c; (void)s; (void)b; (void)n; return fmi2Error; }
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s)
{ (void)c; (void)b; (void)n; (void)s; return fmi2Error; }
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real dv[], fmi2Real dz[])
{ (void)c; (void)u; (void)nu; (void)z; (void)nz; (void)dv; (void)dz; return fmi2Error; }
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer o[], const fmi2Real v[])
{ (void)c; (void)vr; (void)n; (void)o; (void)v; return fmi2Error; }
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer o[], fmi2Real v[])
{ (void)c; (void)vr; (void)n; (void)o; (void)v; return fmi2Error; }
