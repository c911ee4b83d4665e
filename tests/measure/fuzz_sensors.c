/* libFuzzer target for the sensors and MEASURED CSV readers
 * (host/hybrid/measure.h). Any input must give TB_OK or an error status
 * with a message, never a crash, leak or sanitizer report; an accepted
 * sensor set has unique names, unit directions and half-angles in (0, 90]
 * for radiance meters, and the same bytes read as a MEASURED file against
 * it must also end cleanly. Filter names resolve against a folder that does
 * not exist, so no file outside the input is read. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "host/hybrid/measure.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0)
        return 0; /* fmemopen needs a non-empty buffer; the unit tests cover empty files */
    FILE *f = fmemopen((void *)data, size, "rb");
    if (!f)
        return 0;
    tb_sensor_set ss;
    tb_status st = tb_sensors_read_stream(f, "fuzz", "/nonexistent-fuzz-dir", &ss);
    fclose(f);
    if (st != TB_OK) {
        if (ss.n || ss.s || !tb_last_error()[0])
            __builtin_trap(); /* a failed read returns nothing and says why */
        return 0;
    }
    for (int i = 0; i < ss.n; i++) {
        const tb_sensor *s = &ss.s[i];
        const double len = sqrt((double)s->d.x * s->d.x + (double)s->d.y * s->d.y + (double)s->d.z * s->d.z);
        if (!(fabs(len - 1.0) < 1e-5) || !s->name[0])
            __builtin_trap();
        if (s->kind == TB_SENSOR_RADIANCE && !(s->half_angle_deg > 0.0 && s->half_angle_deg <= 90.0))
            __builtin_trap();
        for (int j = 0; j < i; j++)
            if (strcmp(ss.s[j].name, s->name) == 0)
                __builtin_trap();
    }
    FILE *g = fmemopen((void *)data, size, "rb");
    if (g) {
        tb_measured_set ms;
        if (tb_measured_read_stream(g, "fuzz-measured", &ss, &ms) == TB_OK)
            for (int i = 0; i < ms.n; i++)
                if (ms.m[i].sensor < 0 || ms.m[i].sensor >= ss.n || !isfinite(ms.m[i].value))
                    __builtin_trap();
        tb_measured_free(&ms);
        fclose(g);
    }
    tb_sensors_free(&ss);
    return 0;
}
