/* sss_fields.h - the material schema, declared once.
 *
 * SSS_MATERIAL_FIELDS(X) lists every sss_material field that a scene
 * description can set, one X(...) per field:
 *
 *   X(key, member, type, profile, when, d0, d1, d2, lo, hi, lo_open,
 *     names, help)
 *
 *   key      its JSON key in a "materials" entry
 *   member   the sss_material member it sets
 *   type     F32, VEC3 (float[3]), INT or ENUM (an int32_t named by names)
 *   profile  the profile that reads it (ALL: every profile)
 *   when     ALWAYS, or TRANSMITS (checked only when transmission is not
 *            off) or ALBEDO (checked only by a mapping that reads the
 *            albedo)
 *   d0..d2   sss_material_default's value (VEC3: per channel)
 *   lo, hi   the allowed range, lo excluded when lo_open (INT: inclusive;
 *            ENUM: derived from names); hi 1e30 means "no upper bound"
 *   names    ENUM: SSS__NAMES(its table of names, below), else
 *            SSS__NO_NAMES (two arguments once expanded: an X that
 *            reads them goes through a second macro)
 *   help     one line: what it is, for documentation and tooltips; a
 *            length starts with its unit, "metres" or "mm" (the add-on
 *            shows the first in the scene's units, the second in its
 *            label)
 *
 * sss_material.c makes the defaults, the checks and sss_material_field()
 * from it, sss_scene.c the JSON reader's material keys, the add-on its
 * material settings and their scene-description keys (properties.py,
 * description.py), and tests/test_scene.c checks docs/scene.md against
 * it. A new field is one line here and its sss_material member, plus the
 * code that uses it (and, if artists set it, its line in the add-on's
 * panel, ui.py); `make scene-doc` writes its row in docs/scene.md. */
#ifndef SSS_FIELDS_H
#define SSS_FIELDS_H

#include "sss.h"

typedef struct sss__name_value {
	const char *name;
	int32_t value;
} sss__name_value;

/* The names of each enum-valued key, in the order messages list them. */
static const sss__name_value sss__profile_names[] = {
	{"burley", SSS_PROFILE_BURLEY}, {"gaussians", SSS_PROFILE_GAUSSIANS},
	{"jimenez", SSS_PROFILE_JIMENEZ}, {"near-far", SSS_PROFILE_NEAR_FAR},
	{"none", SSS_PROFILE_NONE},
};
static const sss__name_value sss__texturing_names[] = {
	{"post", SSS_TEXTURING_POST},
	{"pre-and-post", SSS_TEXTURING_PRE_AND_POST},
};
static const sss__name_value sss__mapping_names[] = {
	{"cycles", SSS_BURLEY_CYCLES}, {"eevee", SSS_BURLEY_EEVEE},
	{"random-walk", SSS_BURLEY_RANDOM_WALK},
	{"cycles-random-walk", SSS_BURLEY_CYCLES_RANDOM_WALK},
	{"cycles4-random-walk", SSS_BURLEY_CYCLES4_RANDOM_WALK},
};
static const sss__name_value sss__transmission_names[] = {
	{"off", SSS_TRANSMISSION_OFF}, {"burley", SSS_TRANSMISSION_BURLEY},
	{"jimenez", SSS_TRANSMISSION_JIMENEZ},
	{"beer-lambert", SSS_TRANSMISSION_BEER_LAMBERT},
	{"fast", SSS_TRANSMISSION_FAST},
};
static const sss__name_value sss__calibration_names[] = {
	{"none", SSS_CALIBRATION_NONE},
	{"cycles-random-walk", SSS_CALIBRATION_CYCLES_RANDOM_WALK},
	{"cycles4-random-walk-skin", SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN},
	{"cycles4-random-walk", SSS_CALIBRATION_CYCLES4_RANDOM_WALK},
};

#define SSS__COUNT(a) ((int)(sizeof(a) / sizeof *(a)))

/* For X's names argument: the table and its size, or none. */
#define SSS__NAMES(table) sss__##table##_names, SSS__COUNT(sss__##table##_names)
#define SSS__NO_NAMES NULL, 0

/* Ranges: "no upper bound" is 1e30, the largest a float field holds
 * with room to spare. */
#define SSS__BIG 1e30

/* For X's profile argument. */
#define SSS__P_ALL (-1)
#define SSS__P_BURLEY SSS_PROFILE_BURLEY
#define SSS__P_GAUSSIANS SSS_PROFILE_GAUSSIANS
#define SSS__P_JIMENEZ SSS_PROFILE_JIMENEZ
#define SSS__P_NEAR_FAR SSS_PROFILE_NEAR_FAR

/* For X's when argument. */
enum { SSS__WHEN_ALWAYS, SSS__WHEN_TRANSMITS, SSS__WHEN_ALBEDO };

/* clang-format off */
#define SSS_MATERIAL_FIELDS(X) \
X("strength", strength, F32, ALL, ALWAYS, 1.0f, 0, 0, 0, 1, 0, \
  SSS__NO_NAMES, "share of the diffuse light that scatters") \
X("texturing", texturing, ENUM, ALL, ALWAYS, SSS_TEXTURING_POST, 0, 0, \
  0, 0, 0, SSS__NAMES(texturing), \
  "post: texture stays crisp; pre-and-post: it bleeds a little") \
X("taps", taps, INT, ALL, ALWAYS, 0, 0, 0, 0, 4097, 0, SSS__NO_NAMES, \
  "taps per 1-D pass, 0 = the scene's") \
X("radius", radius, VEC3, BURLEY, ALWAYS, 0.00367f, 0.00137f, 0.00068f, \
  0, SSS__BIG, 0, SSS__NO_NAMES, "metres per channel") \
X("mapping", burley_mapping, ENUM, BURLEY, ALWAYS, SSS_BURLEY_CYCLES, 0, \
  0, 0, 0, 0, SSS__NAMES(mapping), "how the radius becomes Burley's d") \
X("albedo", albedo, VEC3, BURLEY, ALBEDO, 0.8f, 0.8f, 0.8f, 0, 1, 0, \
  SSS__NO_NAMES, "the diffuse colour, read by the random-walk mappings") \
X("scale", gaussian_scale, F32, GAUSSIANS, ALWAYS, 1.0f, 0, 0, 0, \
  SSS__BIG, 0, SSS__NO_NAMES, "factor on every radius") \
X("width", jimenez_width, F32, JIMENEZ, ALWAYS, 0.012f, 0, 0, 0, \
  SSS__BIG, 0, SSS__NO_NAMES, "metres: world span of 3 kernel units") \
X("strength_rgb", jimenez_strength, VEC3, JIMENEZ, ALWAYS, 0.48f, 0.41f, \
  0.28f, 0, 1, 0, SSS__NO_NAMES, "share that scatters, per channel") \
X("falloff", jimenez_falloff, VEC3, JIMENEZ, ALWAYS, 1.0f, 0.37f, 0.3f, \
  0, SSS__BIG, 1, SSS__NO_NAMES, "the kernel's falloff per channel") \
X("scatter_scale", scatter_scale, F32, NEAR_FAR, ALWAYS, 1.0f, 0, 0, 0, \
  SSS__BIG, 0, SSS__NO_NAMES, "factor on both sigmas") \
X("balance", near_far_balance, F32, NEAR_FAR, ALWAYS, 0.5f, 0, 0, 0, 1, \
  0, SSS__NO_NAMES, "1 = all near, 0 = all far") \
X("near_sigma", near_sigma, VEC3, NEAR_FAR, ALWAYS, 0.35f, 0.07f, \
  0.035f, 0, SSS__BIG, 1, SSS__NO_NAMES, "mm per channel, the near lobe") \
X("far_sigma", far_sigma, VEC3, NEAR_FAR, ALWAYS, 1.0f, 0.12f, 0.10f, 0, \
  SSS__BIG, 1, SSS__NO_NAMES, "mm per channel, the far lobe") \
X("transmission", transmission, ENUM, ALL, ALWAYS, SSS_TRANSMISSION_OFF, \
  0, 0, 0, 0, 0, SSS__NAMES(transmission), \
  "light through thin parts lit from behind") \
X("transmission_strength", transmission_strength, F32, ALL, TRANSMITS, \
  1.0f, 0, 0, 0, 1, 0, SSS__NO_NAMES, "share of the back light") \
X("transmission_color", transmission_color, VEC3, ALL, TRANSMITS, 1.0f, \
  1.0f, 1.0f, 0, 1, 0, SSS__NO_NAMES, "tint of the transmitted light") \
X("transmission_distance", transmission_distance, F32, ALL, TRANSMITS, \
  0.01f, 0, 0, 0, SSS__BIG, 1, SSS__NO_NAMES, \
  "metres: Beer-Lambert's distance, fast's fade-out thickness") \
X("transmission_translucency", transmission_translucency, F32, ALL, \
  TRANSMITS, 0.83f, 0, 0, 0, 1, 0, SSS__NO_NAMES, \
  "Jimenez's translucency") \
X("transmission_distortion", transmission_distortion, F32, ALL, \
  TRANSMITS, 0.2f, 0, 0, 0, 1, 0, SSS__NO_NAMES, \
  "fast: the normal's shift") \
X("transmission_power", transmission_power, F32, ALL, TRANSMITS, 4.0f, \
  0, 0, 0, SSS__BIG, 1, SSS__NO_NAMES, "fast: the exponent") \
X("transmission_scale", transmission_scale, F32, ALL, TRANSMITS, 1.0f, \
  0, 0, 0, SSS__BIG, 0, SSS__NO_NAMES, "fast: the factor") \
X("transmission_ambient", transmission_ambient, F32, ALL, TRANSMITS, \
  0.0f, 0, 0, 0, SSS__BIG, 0, SSS__NO_NAMES, "fast: the constant term") \
X("thickness_scale", thickness_scale, F32, ALL, TRANSMITS, 1.0f, 0, 0, \
  0, SSS__BIG, 0, SSS__NO_NAMES, "factor on the thickness pass") \
X("transmission_baked_scale", transmission_baked_scale, F32, ALL, \
  TRANSMITS, 0.0f, 0, 0, 0, SSS__BIG, 0, SSS__NO_NAMES, \
  "the radius scale the back light was baked at, 0 = not baked") \
X("thin_reflectance", thin_reflectance, F32, ALL, ALWAYS, 0.0f, 0, 0, 0, \
  1, 0, SSS__NO_NAMES, "share of the measured loss of light thin parts " \
  "reflect (4.x Random Walk (Skin); needs the thickness pass)") \
X("calibration", calibration, ENUM, ALL, ALWAYS, SSS_CALIBRATION_NONE, 0, \
  0, 0, 0, 0, SSS__NAMES(calibration), \
  "the random walk whose energy is matched") \
X("walk_ior", walk_ior, F32, ALL, ALWAYS, 1.5f, 0, 0, 1, 3.8, 0, \
  SSS__NO_NAMES, "the index of the surface the walk enters through " \
  "(4.x Random Walk: from IOR and Specular IOR Level)") \
X("walk_roughness", walk_roughness, F32, ALL, ALWAYS, 0.5f, 0, 0, 0, 1, 0, \
  SSS__NO_NAMES, "that surface's roughness (4.x Random Walk: the " \
  "material's Roughness)")
/* clang-format on */

#endif
