/* sss_camera_fields.h - the camera schema (sss_camera), declared once.
 *
 * SSS_CAMERA_FIELDS(X) lists every sss_camera member but struct_size,
 * one X(...) per member, in the order they are read and documented:
 *
 *   X(key, member, type, place, when, def, lo, hi, lo_open, names, help)
 *
 *   key      its JSON key, Blender's name
 *   member   the sss_camera member it sets
 *   type     ENUM (an int32_t named by names) or F64 (double)
 *   place    CAMERA (a key of the scene description's "camera" object)
 *            or TOP (a key of its top level)
 *   when     ALWAYS, PERSP or ORTHO: the camera types whose check reads
 *            it (the JSON reader checks every key given, whatever the
 *            type: a bad value is a bug in whatever wrote the file)
 *   def      sss_camera_default's value (Blender's default camera)
 *   lo, hi   F64: the allowed range, lo excluded when lo_open; +-SSS__ANY
 *            (the largest doubles) mean no bound but a finite value
 *   names    ENUM: SSS__NAMES(its table of names, below), else
 *            SSS__NO_NAMES
 *   help     one line: what it is; a length's unit first
 *
 * sss_status.c makes sss_camera_default from it, sss_camera.c the
 * camera's check (sss__projection_make, which sss_apply and the scene
 * reader run), sss_scene.c the JSON reader's camera keys and unit_scale,
 * and tests/test_scene.c checks docs/scene.md against it. */
#ifndef SSS_CAMERA_FIELDS_H
#define SSS_CAMERA_FIELDS_H

#include "sss_fields.h"

#include <float.h>

static const sss__name_value sss__camera_type_names[] = {
	{"PERSP", SSS_CAMERA_PERSPECTIVE}, {"ORTHO", SSS_CAMERA_ORTHOGRAPHIC},
};
static const sss__name_value sss__sensor_fit_names[] = {
	{"AUTO", SSS_SENSOR_FIT_AUTO}, {"HORIZONTAL", SSS_SENSOR_FIT_HORIZONTAL},
	{"VERTICAL", SSS_SENSOR_FIT_VERTICAL},
};

/* For F64's lo and hi: no bound, but finite. */
#define SSS__ANY DBL_MAX

/* For X's when argument: the camera types that read it. */
enum { SSS__CAM_ALWAYS, SSS__CAM_PERSP, SSS__CAM_ORTHO };
/* For X's place argument. */
enum { SSS__PLACE_CAMERA, SSS__PLACE_TOP };

/* clang-format off */
#define SSS_CAMERA_FIELDS(X) \
X("type", type, ENUM, CAMERA, ALWAYS, SSS_CAMERA_PERSPECTIVE, 0, 0, 0, \
  SSS__NAMES(camera_type), "perspective or orthographic") \
X("lens", lens_mm, F64, CAMERA, PERSP, 50.0, 0, SSS__ANY, 1, \
  SSS__NO_NAMES, "mm: the focal length") \
X("sensor_width", sensor_width_mm, F64, CAMERA, PERSP, 36.0, 0, SSS__ANY, \
  1, SSS__NO_NAMES, "mm") \
X("sensor_height", sensor_height_mm, F64, CAMERA, PERSP, 24.0, 0, \
  SSS__ANY, 1, SSS__NO_NAMES, "mm") \
X("sensor_fit", sensor_fit, ENUM, CAMERA, ALWAYS, SSS_SENSOR_FIT_AUTO, 0, \
  0, 0, SSS__NAMES(sensor_fit), "which image side the sensor spans") \
X("shift_x", shift_x, F64, CAMERA, ALWAYS, 0.0, -SSS__ANY, SSS__ANY, 0, \
  SSS__NO_NAMES, "fraction of the larger image side") \
X("shift_y", shift_y, F64, CAMERA, ALWAYS, 0.0, -SSS__ANY, SSS__ANY, 0, \
  SSS__NO_NAMES, "fraction of the larger image side") \
X("ortho_scale", ortho_scale, F64, CAMERA, ORTHO, 6.0, 0, SSS__ANY, 1, \
  SSS__NO_NAMES, "scene units: the larger side's span") \
X("pixel_aspect_x", pixel_aspect_x, F64, CAMERA, ALWAYS, 1.0, 0, \
  SSS__ANY, 1, SSS__NO_NAMES, "Blender's render.pixel_aspect_x") \
X("pixel_aspect_y", pixel_aspect_y, F64, CAMERA, ALWAYS, 1.0, 0, \
  SSS__ANY, 1, SSS__NO_NAMES, "Blender's render.pixel_aspect_y") \
X("unit_scale", unit_scale, F64, TOP, ALWAYS, 1.0, 0, SSS__ANY, 1, \
  SSS__NO_NAMES, "metres per scene unit")
/* clang-format on */

#endif
