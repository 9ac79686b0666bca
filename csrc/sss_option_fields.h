/* sss_option_fields.h - the options schema (sss_options), declared once.
 *
 * SSS_OPTION_FIELDS(X) lists every sss_options member, one X(...) per
 * member, in the order they are checked, read and documented:
 *
 *   X(key, member, type, def, lo, hi, lo_open, help)
 *
 *   key      its JSON key at the scene description's top level
 *   member   the sss_options member it sets
 *   type     METHOD (an int32_t named by sss_method_name), F32 (float),
 *            F64 (double) or INT (int32_t)
 *   def      sss_options_default's value
 *   lo, hi   the allowed range, lo excluded when lo_open (INT:
 *            inclusive; METHOD: sss_method_name's values). On a number,
 *            hi SSS__BIG means "no upper bound": the value must be
 *            finite (the JSON reader caps it at 1e30, as every float of
 *            the material schema), and INFINITY "no bound at all", +Inf
 *            included (JSON cannot write it)
 *   help     one line: what it is, for documentation, the add-on and
 *            `sss --help`; a quantity's unit first
 *
 * sss_status.c makes sss_options_default from it, sss_options.c the
 * options' check (sss_apply's, and sss_frame.c's of the radius scale
 * that sss_process_options multiplies), sss_scene.c the JSON reader's
 * top-level keys,
 * sss_option_field() hands it to the `sss` command (its ranges and
 * messages) and the add-on, and tests/test_scene.c checks docs/scene.md
 * against it. */
#ifndef SSS_OPTION_FIELDS_H
#define SSS_OPTION_FIELDS_H

#include "sss_fields.h"

#include <math.h>
#include <stdint.h>

/* clang-format off */
#define SSS_OPTION_FIELDS(X) \
X("method", method, METHOD, SSS_METHOD_AUTO, 0, 0, 0, \
  "how the light is scattered (sss --help lists the methods)") \
X("radius_scale", radius_scale, F32, 1.0, 0, SSS__BIG, 0, \
  "factor on every profile length, 0 = no scattering") \
X("taps", taps, INT, SSS_DEFAULT_TAPS, 1, 4097, 0, \
  "taps per 1-D pass for kernels wider than 64 px") \
X("threads", num_threads, INT, 0, 0, 256, 0, "threads, 0 = all cores") \
X("background_depth", background_depth, F64, 1e9, 0, INFINITY, 1, \
  "scene units: a depth at or past it is background") \
X("max_support_px", max_support_px, INT, 256, 1, INT32_MAX, 0, \
  "pixels: the most a kernel's half-width may be") \
X("samples", samples, INT, 64, 1, 4096, 0, \
  "disk method: most samples per pixel") \
X("crease", crease, INT, 1, 0, 2, 0, \
  "1: calibrated materials carry light over sharp convex edges; 2: the " \
  "blur stops at them but carries nothing over (for measuring the term)")
/* clang-format on */

#endif
