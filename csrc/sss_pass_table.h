/* sss_pass_table.h - Blender's render passes that libsss reads, declared
 * once.
 *
 * SSS_RENDER_PASSES(X) has one X(name, member, components, alt, required,
 * blender, hint) per pass, in the order they are read and checked:
 *
 *   name        the pass's short name in Blender's multilayer EXR
 *   member      the sss_passes member it fills
 *   components  the components read, in order ("RGB"); their count is
 *               the channels sss_apply takes
 *   alt         or this single component (NULL: none)
 *   required    SSS_PASS_OPTIONAL, SSS_PASS_REQUIRED, or
 *               SSS_PASS_CYCLES (required of a Cycles render)
 *   blender     the view layer's property use_pass_<blender>
 *   hint        where to turn it on under View Layer Properties > Passes
 *
 * sss_render_passes.c reads and names passes with it, sss_apply.c checks
 * the caller's views and their aliasing with it, and sss_render_pass()
 * hands it to bindings (the add-on's list of passes it turns on). */
#ifndef SSS_PASS_TABLE_H
#define SSS_PASS_TABLE_H

#include "sss.h"

/* clang-format off */
#define SSS_RENDER_PASSES(X) \
X("DiffDir", diff_dir, "RGB", NULL, SSS_PASS_REQUIRED, "diffuse_direct", \
  "Light > Diffuse: Direct") \
X("DiffInd", diff_ind, "RGB", NULL, SSS_PASS_CYCLES, "diffuse_indirect", \
  "Light > Diffuse: Indirect") \
X("DiffCol", diff_col, "RGB", NULL, SSS_PASS_REQUIRED, "diffuse_color", \
  "Light > Diffuse: Color") \
X("GlossDir", gloss_dir, "RGB", NULL, SSS_PASS_OPTIONAL, "glossy_direct", \
  "Light > Glossy: Direct") \
X("GlossInd", gloss_ind, "RGB", NULL, SSS_PASS_OPTIONAL, \
  "glossy_indirect", "Light > Glossy: Indirect") \
X("GlossCol", gloss_col, "RGB", NULL, SSS_PASS_OPTIONAL, "glossy_color", \
  "Light > Glossy: Color") \
X("TransDir", trans_dir, "RGB", NULL, SSS_PASS_OPTIONAL, \
  "transmission_direct", "Light > Transmission: Direct") \
X("TransInd", trans_ind, "RGB", NULL, SSS_PASS_OPTIONAL, \
  "transmission_indirect", "Light > Transmission: Indirect") \
X("TransCol", trans_col, "RGB", NULL, SSS_PASS_OPTIONAL, \
  "transmission_color", "Light > Transmission: Color") \
X("Emit", emit, "RGB", NULL, SSS_PASS_OPTIONAL, "emit", \
  "Light > Other: Emission") \
X("Env", env, "RGB", NULL, SSS_PASS_OPTIONAL, "environment", \
  "Light > Other: Environment") \
X("Combined", combined, "RGBA", NULL, SSS_PASS_OPTIONAL, "combined", \
  "Data: Combined") \
X("Depth", depth, "Z", "V", SSS_PASS_REQUIRED, "z", "Data: Z") \
X("IndexMA", index_ma, "X", "V", SSS_PASS_REQUIRED, "material_index", \
  "Data: Material Index") \
X("Position", position, "XYZ", NULL, SSS_PASS_OPTIONAL, "position", \
  "Data: Position")
/* clang-format on */

#endif
