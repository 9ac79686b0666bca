/* sss_calibration.c - what Cycles' random-walk SSS does that a blur of
 * the SSS-off render does not, measured on flat slabs
 * (blender_scripts/calibrate.py, Cycles CPU, denoising, adaptive sampling
 * and clamping off): Blender 3.4.1 in sections 1 and 2, 4.5.15 and 5.0.1
 * (4.0 rewrote the random walk) in section 3, all three seen at an angle
 * in section 4.
 *
 * 1. Energy. A box 6 x 6 m wide and 4 m deep (2 x 2 x 1 m for the world
 *    runs), Principled BSDF with Specular 0 and Roughness 0.5, Base Color =
 *    Subsurface Color = A per channel, Subsurface 1 with the radius r per
 *    channel (Subsurface Method Random Walk, IOR 1.4), faces an orthographic
 *    camera that sees 0.2 m of its middle at 64 x 64; the mean Combined
 *    over the central 32 x 32 pixels of the random walk over that of the
 *    same material with Subsurface 0 (the add-on's SSS-off render) is g(A).
 *    Three lightings: a uniform white world (r = 0.05 m and 0.2 m, 256
 *    samples), and a sun at 0 and at 60 degrees from the normal (r = 0.05 m,
 *    128 samples). All agree within their standard errors (0.001 - 0.003):
 *
 *      A      world   sun 0   sun 60   table
 *      0.05   1.0106  1.0100  1.0098   1.010
 *      0.1    1.0113  1.0122  1.0119   1.012
 *      0.2    1.0099  1.0119  1.0116   1.011
 *      0.3    1.0112  1.0146  1.0143   1.013
 *      0.4    1.0114                   1.011
 *      0.5    1.0091  1.0136  1.0133   1.012
 *      0.6    1.0103                   1.010
 *      0.7    1.0111  1.0078  1.0076   1.009
 *      0.8    1.0104  1.0135  1.0132   1.012
 *      0.85   1.0110                   1.011
 *      0.9    1.0060  1.0067  1.0065   1.006
 *      0.95   0.9684  0.9679  0.9687   0.968
 *      0.98   0.9401  0.9385  0.9399   0.9405
 *      0.99   0.9309  0.9290  0.9307   0.9315
 *      1.0    0.9197  0.9167  0.9186   0.9225
 *
 *    On a thick slab the random walk returns the diffuse lobe's energy to
 *    about 1 % up to A = 0.9; above it loses light (its walks are cut off
 *    after a fixed number of steps), and the reflectance A g(A) levels off
 *    at about 0.92. The last three entries are moved within their errors
 *    so that A g(A) never decreases. With r = 0.2 m the ratio grows at
 *    A <= 0.1 (1.11 at 0.1, 1.36 at 0.05); such dark channels are rare and
 *    keep the 0.05 m value. The ratio does not depend on the light's
 *    direction, so it is a property of the albedo. Where it goes: a slab
 *    with 2.5 cm stripes of Base Color (0.9, 0.8, 0.7) / (0.3, 0.15, 0.1)
 *    under the sun (r = 0.02 and 0.1 m) renders with the random walk as
 *    crisp as with SSS off (RMSE 0.044 between them, the noise): Cycles'
 *    random walk takes the colour where light leaves, i.e. post-scatter
 *    texturing (pre-and-post: RMSE 0.080 and 0.134). So the gain acts as a
 *    brighter diffuse colour at the exit pixel: the scattered light of a
 *    pixel is scaled by g(DiffCol) there, after the blur, in both
 *    texturing modes (the blend with strength m: 1 + m (g - 1)).
 *
 * 2. Shape. The same box under a sun at normal incidence, the left half in
 *    the shadow of a plate that only casts shadows (5 cm in front of the
 *    face), r = 0.3 m, 0.4 m seen at 128 x 128, pixel filter 0.01 px, 128
 *    samples: the edge profile of the random walk (averaged along the
 *    edge) is fitted with Burley's edge response (least squares in d and
 *    an energy factor). Fitted d / r (r = 0.05 m at 0.2 m gave the same to
 *    4 %) against Cycles' own radius conversion for the random walk
 *    followed by Christensen-Burley's searchlight fit:
 *
 *      A      d/r fit  this mapping  random-walk (C&B dmfp)
 *      0.1    0.316    0.313         0.265
 *      0.2    0.261    0.253         0.283
 *      0.3    0.210    0.209         0.286
 *      0.4    0.178    0.177         0.286
 *      0.5    0.145    0.151         0.279
 *      0.6    0.121    0.126         0.248
 *      0.7    0.098    0.099         0.186
 *      0.8    0.067    0.067         0.119
 *      0.85   0.046    0.050         0.092
 *      0.9    0.034    0.033         0.071
 *      0.93   0.032    0.032 (floor) 0.061
 *      0.95   0.034    0.032 (floor) 0.055
 *      0.99   0.032    0.032 (floor) 0.044
 *    (cycles: 0.0796 and eevee: 0.0459 for every A.) A = 1 fits below
 *    0.01 (Cycles takes a' = 0.999999 from A = 0.995 on), as here.
 *
 *    This mapping is within 4 % of the fit up to A = 0.9 (8 % at 0.85); below
 *    d = 0.032 r the measured profile stops narrowing, and this mapping
 *    keeps that floor. Every older mapping is off by up to 4x somewhere.
 *    Edge-profile RMSE (profiles over the SSS-off lit plateau; libsss,
 *    separable-exact, on the SSS-off render of the same slab), per mapping
 *    cycles / eevee / random-walk: A 0.3: 0.107 / 0.146 / 0.019; 0.5:
 *    0.063 / 0.103 / 0.040; 0.7: 0.021 / 0.061 / 0.051; 0.8: 0.018 /
 *    0.028 / 0.048; 0.9: 0.064 / 0.026 / 0.056; 0.95: 0.054 / 0.027 /
 *    0.033 - each older mapping wins only where its d crosses the fit.
 *
 * 3. Blender 4.5.15 and 5.0.1 (Principled v2, Subsurface Weight 1, Scale
 *    x Radius = r, IOR Level 0, default Subsurface IOR and Anisotropy),
 *    the same protocols. 5.0.1 measures as 4.5.15 within the errors
 *    (0.003 at most apart), so one table serves 4.x and 5.x. On the
 *    infinite slab the ratio is now the same to 4 digits for the white
 *    world, a sun at 0 and at 60 degrees and r = 0.05, 0.2 and 0.3 m
 *    (standard errors 0.0005 - 0.003):
 *
 *      A      Skin 4.5  Skin 5.0  RW 4.5  RW 5.0
 *      0.05   0.9036    0.9031    0.7686  0.7703
 *      0.1    0.9087    0.9079    0.7808  0.7827
 *      0.2    0.9196    0.9199    0.8054  0.8080
 *      0.3    0.9317    0.9297    0.8328  0.8293
 *      0.4    0.9436    0.9415    0.8575  0.8558
 *      0.5    0.9545    0.9535    0.8819  0.8815
 *      0.6    0.9646    0.9633    0.9059  0.9055
 *      0.7    0.9763    0.9753    0.9318  0.9323
 *      0.8    0.9889    0.9896    0.9609  0.9616
 *      0.85   0.9951    0.9975    0.9722  0.9737
 *      0.9    0.9916    0.9921    0.9763  0.9782
 *      0.95   0.9546    0.9552    0.9416  0.9435
 *      0.98   0.9262    0.9282    0.9128  0.9147
 *      0.99   0.9168    0.9189    0.9036  0.9054
 *      1.0    0.9055    0.9062    0.8945  0.8964
 *
 *    (the tables: 4.5's, A = 0 as at 0.05, A = 0.99 and 1 moved within
 *    their errors so that A g(A) never decreases; between the points
 *    the reflectance A g(A) is interpolated, not g). Random Walk (Skin), the
 *    3.x walk, now loses up to 10 % at low albedo where 3.4's kept 1 %
 *    more than the diffuse lobe; Random Walk loses up to 23 %; both level
 *    off at a reflectance of about 0.90.
 *
 *    Shape (r = 0.3 m, 0.4 m at 128 x 128): Random Walk (Skin) fits d / r
 *    = 0.316 0.293 0.242 0.207 0.171 0.147 0.121 0.100 0.068 0.052 0.032
 *    0.033 at A = 0.05 0.1 0.2 ... 0.8 0.85 0.9 0.95, 3.4's mapping
 *    within 5 % (8 % at 0.85): it keeps SSS_BURLEY_CYCLES_RANDOM_WALK.
 *    Random Walk widens the other way, with the albedo:
 *
 *      A      0.05   0.1    0.2    0.3    0.4    0.5    0.6    0.7
 *      d/r    0.0171 0.0192 0.0251 0.0304 0.0369 0.0447 0.0541 0.0656
 *      A      0.8    0.85   0.9    0.95 .. 1
 *      d/r    0.0825 0.0891 0.100  0.1039
 *
 *    (r = 0.05 m at 64 x 64 gave the same within 10 %, below a pixel at
 *    low A), and SSS_BURLEY_CYCLES4_RANDOM_WALK interpolates it. 5.0.1:
 *    the same fits within 4 % (one step of the fit's grid), for both walks.
 *
 * 4. View. Sections 1 and 3 looked at the face head-on. Turned about its
 *    vertical axis so that the camera sees it at 30, 45, 60, 70, 80 and 85
 *    degrees from its normal (calibrate.py --view-angles; white world,
 *    r = 0.05 m, 128 samples, 48 x 48, standard errors 0.002 - 0.005), the
 *    random walk's energy over the diffuse lobe's grows with the angle, on
 *    every version: 4.5.15's Random Walk (Skin) goes from 0.898 head-on to
 *    1.04 at 60 and 1.27 at 85 degrees at A = 0.05 (0.954, 1.029, 1.114 at
 *    A = 0.5), its Random Walk from 0.768 to 1.10 and 1.76; 3.4.1's walk
 *    from 1.01 to 1.025 and 1.32 at every A up to 0.9. 5.0.1 measures as
 *    4.5.15 (60 and 85 degrees, A = 0.05, 0.5, 0.9: within 0.03, 0.003,
 *    0.002). So the gain is g(A, mu), mu the cosine of the view angle,
 *    which the library takes per pixel from the Depth pass
 *    (sss__view_cosine). Head-on gains alone made every bundled scene
 *    worse than no calibration on 4.5 (by 1.4 - 1.8x the quarter-
 *    resolution error of the render without SSS where the kernel is under
 *    a pixel): a sphere shows every angle, and its mean gain is near 1.
 *    The rows below are this run (head-on within the errors of sections 1
 *    and 3); A = 0 is as 0.05, and entries at A >= 0.9 are moved up by at
 *    most 0.006 (3.4 at A = 1), most by 0.0002, so that A g(A) never
 *    decreases.
 */
#include "sss_internal.h"

#include <string.h>

/* Reflectance of the random walk over the Principled diffuse lobe's, at
 * the albedos of cal_albedo seen at the angles of cal_view_cosine, per
 * calibration (section 4; the 0-degree rows are sections 1 and 3 measured
 * again in the same runs). */
static const float cal_albedo[] = {0.0f, 0.05f, 0.1f, 0.2f, 0.3f, 0.4f, 0.5f,
                                   0.6f, 0.7f, 0.8f, 0.85f, 0.9f, 0.95f,
                                   0.98f, 0.99f, 1.0f};
#define CAL_N ((int)(sizeof cal_albedo / sizeof *cal_albedo))
/* cos of 0, 30, 45, 60, 70, 80 and 85 degrees */
static const float cal_view_cosine[] = {1.0f, 0.8660254f, 0.7071068f, 0.5f,
                                        0.3420201f, 0.1736482f, 0.0871557f};
#define VIEW_N ((int)(sizeof cal_view_cosine / sizeof *cal_view_cosine))
static const float cal_gain[][VIEW_N][CAL_N] = {
	[SSS_CALIBRATION_CYCLES_RANDOM_WALK] = {
		/* 0 degrees */
		{1.0090f, 1.0090f, 1.0092f, 1.0086f, 1.0138f, 1.0117f, 1.0081f, 1.0135f,
		 1.0104f, 1.0080f, 1.0129f, 1.0037f, 0.9662f, 0.9396f, 0.9304f, 0.9211f},
		/* 30 degrees */
		{1.0087f, 1.0087f, 1.0099f, 1.0088f, 1.0133f, 1.0123f, 1.0090f, 1.0168f,
		 1.0104f, 1.0100f, 1.0157f, 1.0034f, 0.9657f, 0.9411f, 0.9319f, 0.9226f},
		/* 45 degrees */
		{1.0122f, 1.0122f, 1.0127f, 1.0112f, 1.0146f, 1.0136f, 1.0105f, 1.0192f,
		 1.0118f, 1.0112f, 1.0174f, 1.0056f, 0.9679f, 0.9420f, 0.9327f, 0.9234f},
		/* 60 degrees */
		{1.0249f, 1.0249f, 1.0254f, 1.0251f, 1.0298f, 1.0276f, 1.0248f, 1.0322f,
		 1.0261f, 1.0253f, 1.0314f, 1.0196f, 0.9820f, 0.9576f, 0.9484f, 0.9390f},
		/* 70 degrees */
		{1.0691f, 1.0691f, 1.0696f, 1.0698f, 1.0735f, 1.0723f, 1.0696f, 1.0746f,
		 1.0701f, 1.0705f, 1.0750f, 1.0631f, 1.0258f, 1.0016f, 0.9925f, 0.9826f},
		/* 80 degrees */
		{1.1975f, 1.1975f, 1.1974f, 1.1953f, 1.1970f, 1.1959f, 1.1941f, 1.1996f,
		 1.1934f, 1.1952f, 1.1986f, 1.1875f, 1.1505f, 1.1271f, 1.1181f, 1.1070f},
		/* 85 degrees */
		{1.3159f, 1.3159f, 1.3157f, 1.3145f, 1.3165f, 1.3154f, 1.3133f, 1.3184f,
		 1.3126f, 1.3147f, 1.3178f, 1.3073f, 1.2702f, 1.2462f, 1.2371f, 1.2248f},
	},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN] = {
		/* 0 degrees */
		{0.8975f, 0.8975f, 0.9054f, 0.9189f, 0.9275f, 0.9416f, 0.9537f, 0.9619f,
		 0.9758f, 0.9888f, 0.9940f, 0.9923f, 0.9553f, 0.9263f, 0.9170f, 0.9091f},
		/* 30 degrees */
		{0.9282f, 0.9282f, 0.9353f, 0.9468f, 0.9537f, 0.9654f, 0.9738f, 0.9794f,
		 0.9889f, 0.9991f, 1.0023f, 0.9980f, 0.9602f, 0.9309f, 0.9215f, 0.9132f},
		/* 45 degrees */
		{0.9729f, 0.9729f, 0.9777f, 0.9836f, 0.9876f, 0.9939f, 0.9971f, 0.9984f,
		 1.0021f, 1.0084f, 1.0108f, 1.0025f, 0.9641f, 0.9351f, 0.9257f, 0.9165f},
		/* 60 degrees */
		{1.0423f, 1.0423f, 1.0422f, 1.0392f, 1.0347f, 1.0328f, 1.0294f, 1.0267f,
		 1.0215f, 1.0210f, 1.0217f, 1.0077f, 0.9683f, 0.9394f, 0.9300f, 0.9210f},
		/* 70 degrees */
		{1.1048f, 1.1048f, 1.1005f, 1.0898f, 1.0768f, 1.0684f, 1.0578f, 1.0488f,
		 1.0384f, 1.0304f, 1.0273f, 1.0131f, 0.9729f, 0.9436f, 0.9341f, 0.9248f},
		/* 80 degrees */
		{1.2035f, 1.2035f, 1.1889f, 1.1607f, 1.1357f, 1.1147f, 1.0927f, 1.0739f,
		 1.0568f, 1.0415f, 1.0349f, 1.0185f, 0.9773f, 0.9483f, 0.9388f, 0.9295f},
		/* 85 degrees */
		{1.2665f, 1.2665f, 1.2448f, 1.2055f, 1.1716f, 1.1425f, 1.1137f, 1.0891f,
		 1.0681f, 1.0478f, 1.0379f, 1.0215f, 0.9799f, 0.9508f, 0.9412f, 0.9318f},
	},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK] = {
		/* 0 degrees */
		{0.7675f, 0.7675f, 0.7804f, 0.8058f, 0.8306f, 0.8556f, 0.8806f, 0.9048f,
		 0.9313f, 0.9606f, 0.9733f, 0.9780f, 0.9435f, 0.9147f, 0.9055f, 0.8965f},
		/* 30 degrees */
		{0.8353f, 0.8353f, 0.8465f, 0.8674f, 0.8866f, 0.9058f, 0.9242f, 0.9404f,
		 0.9594f, 0.9804f, 0.9883f, 0.9886f, 0.9525f, 0.9234f, 0.9141f, 0.9050f},
		/* 45 degrees */
		{0.9320f, 0.9320f, 0.9395f, 0.9523f, 0.9630f, 0.9724f, 0.9804f, 0.9859f,
		 0.9935f, 1.0029f, 1.0050f, 1.0005f, 0.9626f, 0.9332f, 0.9238f, 0.9146f},
		/* 60 degrees */
		{1.0980f, 1.0980f, 1.0963f, 1.0910f, 1.0830f, 1.0742f, 1.0641f, 1.0520f,
		 1.0421f, 1.0341f, 1.0278f, 1.0162f, 0.9757f, 0.9459f, 0.9364f, 0.9271f},
		/* 70 degrees */
		{1.2732f, 1.2732f, 1.2585f, 1.2285f, 1.1982f, 1.1686f, 1.1392f, 1.1096f,
		 1.0830f, 1.0595f, 1.0460f, 1.0286f, 0.9860f, 0.9559f, 0.9463f, 0.9369f},
		/* 80 degrees */
		{1.5461f, 1.5461f, 1.5056f, 1.4287f, 1.3573f, 1.2938f, 1.2353f, 1.1797f,
		 1.1312f, 1.0887f, 1.0672f, 1.0428f, 0.9977f, 0.9672f, 0.9575f, 0.9480f},
		/* 85 degrees */
		{1.7604f, 1.7604f, 1.6942f, 1.5743f, 1.4684f, 1.3775f, 1.2970f, 1.2244f,
		 1.1612f, 1.1063f, 1.0793f, 1.0508f, 1.0044f, 0.9737f, 0.9639f, 0.9543f},
	},
};

/* 4.x's plain Random Walk enters through the material's own surface, of
 * index eta (Cycles: from the Principled BSDF's IOR and Specular IOR
 * Level; bssrdf->ior) and roughness (its Roughness; bssrdf->alpha), and
 * its gain at an angle follows both: the table above is eta = 1.01
 * (Specular IOR Level 0, what every other part of the calibration
 * measured; roughness 0.5, through which the roughness moves the gain by
 * under 1.5 % up to 70 degrees and 8 % at 85), these are 1.5 (Level 0.5
 * with IOR 1.5, Principled's defaults) and 1.79 (Level 1) at roughness
 * 0.1, 0.25, 0.5 and 1 (calibrate.py --part energy --specular 0.5 / 1
 * --roughness R, white world, r = 5 cm, 48 x 48, 128 samples, the
 * diffuse passes' ratio: standard errors under 0.006). At 70 degrees and
 * A = 0.05 the gain is 1.27 through 1.01, and through 1.5 0.89 / 0.90 /
 * 0.97 / 1.19 from roughness 0.1 to 1; head-on it moves by 2 - 4 %. */
static const float rw4_eta[] = {1.01f, 1.5f, 1.7887f};
#define RW4_ETA_N ((int)(sizeof rw4_eta / sizeof *rw4_eta))
static const float rw4_roughness[] = {0.1f, 0.25f, 0.5f, 1.0f};
#define RW4_ROUGH_N ((int)(sizeof rw4_roughness / sizeof *rw4_roughness))
static const float rw4_gain[RW4_ETA_N - 1][RW4_ROUGH_N][VIEW_N][CAL_N] = {
	{ /* eta 1.5 */
		{ /* roughness 0.1 */
			{0.7681f, 0.7681f, 0.7808f, 0.8063f, 0.8309f, 0.8559f,
			 0.8808f, 0.9047f, 0.9312f, 0.9606f, 0.9733f, 0.9780f,
			 0.9435f, 0.9147f, 0.9055f, 0.8965f}, /* 0 */
			{0.7964f, 0.7964f, 0.8086f, 0.8323f, 0.8551f, 0.8779f,
			 0.9001f, 0.9208f, 0.9443f, 0.9703f, 0.9803f, 0.9828f,
			 0.9475f, 0.9185f, 0.9093f, 0.9003f}, /* 30 */
			{0.8294f, 0.8294f, 0.8407f, 0.8620f, 0.8817f, 0.9017f,
			 0.9206f, 0.9373f, 0.9569f, 0.9787f, 0.9869f, 0.9878f,
			 0.9518f, 0.9227f, 0.9134f, 0.9043f}, /* 45 */
			{0.8678f, 0.8678f, 0.8775f, 0.8957f, 0.9118f, 0.9279f,
			 0.9429f, 0.9554f, 0.9707f, 0.9880f, 0.9935f, 0.9922f,
			 0.9555f, 0.9263f, 0.9170f, 0.9079f}, /* 60 */
			{0.8913f, 0.8913f, 0.9005f, 0.9169f, 0.9298f, 0.9439f,
			 0.9567f, 0.9666f, 0.9790f, 0.9934f, 0.9978f, 0.9951f,
			 0.9579f, 0.9286f, 0.9193f, 0.9102f}, /* 70 */
			{0.9035f, 0.9035f, 0.9125f, 0.9289f, 0.9426f, 0.9548f,
			 0.9658f, 0.9751f, 0.9857f, 0.9980f, 1.0008f, 0.9973f,
			 0.9597f, 0.9304f, 0.9211f, 0.9119f}, /* 80 */
			{0.9130f, 0.9130f, 0.9227f, 0.9380f, 0.9454f, 0.9574f,
			 0.9678f, 0.9774f, 0.9873f, 0.9987f, 1.0026f, 0.9990f,
			 0.9614f, 0.9320f, 0.9226f, 0.9134f}, /* 85 */
		},
		{ /* roughness 0.25 */
			{0.7687f, 0.7687f, 0.7815f, 0.8069f, 0.8312f, 0.8562f,
			 0.8811f, 0.9050f, 0.9315f, 0.9608f, 0.9735f, 0.9782f,
			 0.9436f, 0.9148f, 0.9056f, 0.8966f}, /* 0 */
			{0.7981f, 0.7981f, 0.8101f, 0.8337f, 0.8561f, 0.8789f,
			 0.9010f, 0.9214f, 0.9447f, 0.9705f, 0.9806f, 0.9831f,
			 0.9478f, 0.9188f, 0.9096f, 0.9006f}, /* 30 */
			{0.8319f, 0.8319f, 0.8431f, 0.8643f, 0.8833f, 0.9031f,
			 0.9219f, 0.9383f, 0.9577f, 0.9792f, 0.9872f, 0.9880f,
			 0.9520f, 0.9229f, 0.9136f, 0.9045f}, /* 45 */
			{0.8739f, 0.8739f, 0.8833f, 0.9007f, 0.9161f, 0.9316f,
			 0.9460f, 0.9575f, 0.9723f, 0.9891f, 0.9943f, 0.9928f,
			 0.9560f, 0.9268f, 0.9175f, 0.9084f}, /* 60 */
			{0.9028f, 0.9028f, 0.9111f, 0.9259f, 0.9373f, 0.9501f,
			 0.9617f, 0.9702f, 0.9817f, 0.9952f, 0.9989f, 0.9959f,
			 0.9585f, 0.9293f, 0.9200f, 0.9108f}, /* 70 */
			{0.9250f, 0.9250f, 0.9331f, 0.9467f, 0.9601f, 0.9697f,
			 0.9781f, 0.9829f, 0.9915f, 1.0017f, 1.0031f, 0.9985f,
			 0.9606f, 0.9313f, 0.9219f, 0.9127f}, /* 80 */
			{0.9502f, 0.9502f, 0.9574f, 0.9689f, 0.9771f, 0.9842f,
			 0.9900f, 0.9944f, 1.0000f, 1.0074f, 1.0073f, 1.0017f,
			 0.9634f, 0.9340f, 0.9246f, 0.9154f}, /* 85 */
		},
		{ /* roughness 0.5 */
			{0.7761f, 0.7761f, 0.7888f, 0.8139f, 0.8366f, 0.8609f,
			 0.8851f, 0.9080f, 0.9338f, 0.9624f, 0.9743f, 0.9787f,
			 0.9440f, 0.9152f, 0.9060f, 0.8970f}, /* 0 */
			{0.8086f, 0.8086f, 0.8202f, 0.8430f, 0.8640f, 0.8856f,
			 0.9067f, 0.9261f, 0.9483f, 0.9729f, 0.9825f, 0.9843f,
			 0.9488f, 0.9198f, 0.9106f, 0.9015f}, /* 30 */
			{0.8499f, 0.8499f, 0.8605f, 0.8803f, 0.8976f, 0.9154f,
			 0.9322f, 0.9466f, 0.9639f, 0.9833f, 0.9905f, 0.9901f,
			 0.9537f, 0.9246f, 0.9153f, 0.9062f}, /* 45 */
			{0.9137f, 0.9137f, 0.9220f, 0.9358f, 0.9465f, 0.9577f,
			 0.9677f, 0.9746f, 0.9852f, 0.9975f, 1.0005f, 0.9971f,
			 0.9596f, 0.9303f, 0.9210f, 0.9118f}, /* 60 */
			{0.9738f, 0.9738f, 0.9783f, 0.9854f, 0.9895f, 0.9945f,
			 0.9981f, 0.9995f, 1.0034f, 1.0093f, 1.0089f, 1.0029f,
			 0.9644f, 0.9350f, 0.9256f, 0.9164f}, /* 70 */
			{1.0716f, 1.0716f, 1.0698f, 1.0644f, 1.0569f, 1.0508f,
			 1.0439f, 1.0348f, 1.0290f, 1.0253f, 1.0210f, 1.0112f,
			 0.9714f, 0.9417f, 0.9322f, 0.9229f}, /* 80 */
			{1.1484f, 1.1484f, 1.1402f, 1.1231f, 1.1070f, 1.0919f,
			 1.0768f, 1.0611f, 1.0476f, 1.0369f, 1.0293f, 1.0170f,
			 0.9763f, 0.9465f, 0.9370f, 0.9277f}, /* 85 */
		},
		{ /* roughness 1.0 */
			{0.8030f, 0.8030f, 0.8147f, 0.8377f, 0.8585f, 0.8803f,
			 0.9017f, 0.9224f, 0.9447f, 0.9697f, 0.9796f, 0.9824f,
			 0.9471f, 0.9182f, 0.9090f, 0.9000f}, /* 0 */
			{0.8614f, 0.8614f, 0.8716f, 0.8903f, 0.9067f, 0.9229f,
			 0.9382f, 0.9511f, 0.9674f, 0.9856f, 0.9918f, 0.9909f,
			 0.9543f, 0.9251f, 0.9158f, 0.9067f}, /* 30 */
			{0.9429f, 0.9429f, 0.9494f, 0.9603f, 0.9669f, 0.9752f,
			 0.9822f, 0.9872f, 0.9943f, 1.0032f, 1.0051f, 1.0006f,
			 0.9626f, 0.9333f, 0.9239f, 0.9147f}, /* 45 */
			{1.0736f, 1.0736f, 1.0720f, 1.0672f, 1.0580f, 1.0523f,
			 1.0456f, 1.0369f, 1.0308f, 1.0267f, 1.0221f, 1.0123f,
			 0.9725f, 0.9428f, 0.9333f, 0.9240f}, /* 60 */
			{1.1958f, 1.1958f, 1.1860f, 1.1651f, 1.1408f, 1.1207f,
			 1.1005f, 1.0794f, 1.0611f, 1.0456f, 1.0359f, 1.0217f,
			 0.9803f, 0.9503f, 0.9408f, 0.9314f}, /* 70 */
			{1.3648f, 1.3648f, 1.3406f, 1.2933f, 1.2456f, 1.2048f,
			 1.1662f, 1.1287f, 1.0957f, 1.0670f, 1.0516f, 1.0322f,
			 0.9890f, 0.9588f, 0.9492f, 0.9398f}, /* 80 */
			{1.4815f, 1.4815f, 1.4446f, 1.3754f, 1.3119f, 1.2563f,
			 1.2054f, 1.1570f, 1.1152f, 1.0787f, 1.0598f, 1.0377f,
			 0.9935f, 0.9631f, 0.9534f, 0.9439f}, /* 85 */
		},
	},
	{ /* eta 1.7887 */
		{ /* roughness 0.1 */
			{0.7700f, 0.7700f, 0.7822f, 0.8067f, 0.8310f, 0.8559f,
			 0.8808f, 0.9047f, 0.9313f, 0.9607f, 0.9733f, 0.9780f,
			 0.9434f, 0.9146f, 0.9054f, 0.8964f}, /* 0 */
			{0.7896f, 0.7896f, 0.8017f, 0.8253f, 0.8489f, 0.8723f,
			 0.8953f, 0.9162f, 0.9408f, 0.9679f, 0.9784f, 0.9815f,
			 0.9464f, 0.9175f, 0.9083f, 0.8993f}, /* 30 */
			{0.8121f, 0.8121f, 0.8236f, 0.8458f, 0.8664f, 0.8880f,
			 0.9088f, 0.9276f, 0.9495f, 0.9738f, 0.9834f, 0.9852f,
			 0.9497f, 0.9207f, 0.9114f, 0.9023f}, /* 45 */
			{0.8376f, 0.8376f, 0.8477f, 0.8675f, 0.8845f, 0.9042f,
			 0.9229f, 0.9392f, 0.9584f, 0.9799f, 0.9873f, 0.9878f,
			 0.9517f, 0.9226f, 0.9133f, 0.9042f}, /* 60 */
			{0.8491f, 0.8491f, 0.8592f, 0.8786f, 0.8963f, 0.9145f,
			 0.9316f, 0.9458f, 0.9634f, 0.9832f, 0.9892f, 0.9890f,
			 0.9527f, 0.9236f, 0.9143f, 0.9052f}, /* 70 */
			{0.8584f, 0.8584f, 0.8682f, 0.8873f, 0.9027f, 0.9201f,
			 0.9364f, 0.9524f, 0.9685f, 0.9866f, 0.9918f, 0.9910f,
			 0.9544f, 0.9252f, 0.9159f, 0.9068f}, /* 80 */
			{0.8670f, 0.8670f, 0.8775f, 0.8951f, 0.9072f, 0.9238f,
			 0.9391f, 0.9544f, 0.9699f, 0.9871f, 0.9936f, 0.9926f,
			 0.9560f, 0.9268f, 0.9175f, 0.9084f}, /* 85 */
		},
		{ /* roughness 0.25 */
			{0.7701f, 0.7701f, 0.7826f, 0.8074f, 0.8315f, 0.8565f,
			 0.8814f, 0.9049f, 0.9315f, 0.9609f, 0.9735f, 0.9780f,
			 0.9434f, 0.9146f, 0.9054f, 0.8964f}, /* 0 */
			{0.7926f, 0.7926f, 0.8045f, 0.8278f, 0.8506f, 0.8736f,
			 0.8963f, 0.9174f, 0.9416f, 0.9684f, 0.9789f, 0.9818f,
			 0.9466f, 0.9177f, 0.9085f, 0.8995f}, /* 30 */
			{0.8161f, 0.8161f, 0.8272f, 0.8488f, 0.8691f, 0.8902f,
			 0.9106f, 0.9294f, 0.9508f, 0.9746f, 0.9841f, 0.9857f,
			 0.9501f, 0.9211f, 0.9118f, 0.9027f}, /* 45 */
			{0.8439f, 0.8439f, 0.8538f, 0.8728f, 0.8889f, 0.9079f,
			 0.9260f, 0.9420f, 0.9606f, 0.9813f, 0.9885f, 0.9887f,
			 0.9526f, 0.9235f, 0.9142f, 0.9051f}, /* 60 */
			{0.8606f, 0.8606f, 0.8703f, 0.8884f, 0.9033f, 0.9206f,
			 0.9368f, 0.9503f, 0.9668f, 0.9852f, 0.9911f, 0.9903f,
			 0.9538f, 0.9248f, 0.9155f, 0.9064f}, /* 70 */
			{0.8780f, 0.8780f, 0.8872f, 0.9043f, 0.9205f, 0.9349f,
			 0.9485f, 0.9595f, 0.9738f, 0.9901f, 0.9946f, 0.9927f,
			 0.9558f, 0.9266f, 0.9173f, 0.9082f}, /* 80 */
			{0.8999f, 0.8999f, 0.9079f, 0.9224f, 0.9324f, 0.9456f,
			 0.9576f, 0.9693f, 0.9811f, 0.9948f, 0.9984f, 0.9955f,
			 0.9582f, 0.9289f, 0.9196f, 0.9105f}, /* 85 */
		},
		{ /* roughness 0.5 */
			{0.7816f, 0.7816f, 0.7937f, 0.8177f, 0.8396f, 0.8635f,
			 0.8873f, 0.9099f, 0.9353f, 0.9634f, 0.9749f, 0.9789f,
			 0.9441f, 0.9152f, 0.9060f, 0.8970f}, /* 0 */
			{0.8042f, 0.8042f, 0.8161f, 0.8392f, 0.8606f, 0.8827f,
			 0.9043f, 0.9239f, 0.9466f, 0.9718f, 0.9817f, 0.9838f,
			 0.9483f, 0.9193f, 0.9101f, 0.9010f}, /* 30 */
			{0.8369f, 0.8369f, 0.8478f, 0.8683f, 0.8876f, 0.9062f,
			 0.9240f, 0.9403f, 0.9590f, 0.9800f, 0.9881f, 0.9885f,
			 0.9524f, 0.9233f, 0.9140f, 0.9049f}, /* 45 */
			{0.8907f, 0.8907f, 0.8990f, 0.9140f, 0.9248f, 0.9386f,
			 0.9514f, 0.9616f, 0.9753f, 0.9909f, 0.9955f, 0.9936f,
			 0.9567f, 0.9275f, 0.9182f, 0.9091f}, /* 60 */
			{0.9376f, 0.9376f, 0.9434f, 0.9530f, 0.9597f, 0.9688f,
			 0.9767f, 0.9820f, 0.9902f, 1.0006f, 1.0023f, 0.9983f,
			 0.9606f, 0.9312f, 0.9218f, 0.9126f}, /* 70 */
			{1.0147f, 1.0147f, 1.0161f, 1.0166f, 1.0156f, 1.0157f,
			 1.0151f, 1.0115f, 1.0119f, 1.0145f, 1.0125f, 1.0051f,
			 0.9662f, 0.9367f, 0.9273f, 0.9181f}, /* 80 */
			{1.0800f, 1.0800f, 1.0764f, 1.0684f, 1.0596f, 1.0519f,
			 1.0441f, 1.0348f, 1.0286f, 1.0250f, 1.0205f, 1.0108f,
			 0.9711f, 0.9415f, 0.9320f, 0.9227f}, /* 85 */
		},
		{ /* roughness 1.0 */
			{0.8239f, 0.8239f, 0.8347f, 0.8559f, 0.8738f, 0.8939f,
			 0.9134f, 0.9314f, 0.9517f, 0.9744f, 0.9830f, 0.9847f,
			 0.9491f, 0.9201f, 0.9109f, 0.9018f}, /* 0 */
			{0.8796f, 0.8796f, 0.8889f, 0.9057f, 0.9199f, 0.9343f,
			 0.9476f, 0.9590f, 0.9732f, 0.9894f, 0.9940f, 0.9924f,
			 0.9555f, 0.9263f, 0.9170f, 0.9079f}, /* 30 */
			{0.9560f, 0.9560f, 0.9616f, 0.9707f, 0.9757f, 0.9824f,
			 0.9879f, 0.9916f, 0.9974f, 1.0052f, 1.0066f, 1.0017f,
			 0.9636f, 0.9342f, 0.9248f, 0.9156f}, /* 45 */
			{1.0772f, 1.0772f, 1.0748f, 1.0688f, 1.0589f, 1.0525f,
			 1.0453f, 1.0361f, 1.0301f, 1.0260f, 1.0215f, 1.0119f,
			 0.9721f, 0.9424f, 0.9329f, 0.9236f}, /* 60 */
			{1.1839f, 1.1839f, 1.1745f, 1.1542f, 1.1322f, 1.1130f,
			 1.0938f, 1.0742f, 1.0572f, 1.0429f, 1.0338f, 1.0203f,
			 0.9791f, 0.9492f, 0.9397f, 0.9304f}, /* 70 */
			{1.3312f, 1.3312f, 1.3090f, 1.2657f, 1.2231f, 1.1863f,
			 1.1514f, 1.1168f, 1.0873f, 1.0617f, 1.0477f, 1.0295f,
			 0.9867f, 0.9565f, 0.9469f, 0.9375f}, /* 80 */
			{1.4272f, 1.4272f, 1.3951f, 1.3345f, 1.2780f, 1.2292f,
			 1.1842f, 1.1409f, 1.1040f, 1.0718f, 1.0547f, 1.0342f,
			 0.9906f, 0.9603f, 0.9506f, 0.9411f}, /* 85 */
		},
	},
};

/* The interval [cal_albedo[i - 1], cal_albedo[i]] holding a (searched from
 * i = first; a in (cal_albedo[first - 1], 1)) and a's place t in it. */
static int interval(float a, int first, float *t)
{
	int i = first;
	while (i < CAL_N - 1 && cal_albedo[i] < a)
		i++;
	*t = (a - cal_albedo[i - 1]) / (cal_albedo[i] - cal_albedo[i - 1]);
	return i;
}

/* Piecewise linear in cal_albedo, clamped at both ends; 1 for NaN. */
static float lerp_table(const float *table, float a)
{
	if (!isfinite(a))
		return 1.0f;
	if (a <= 0.0f)
		return table[0];
	if (a >= 1.0f)
		return table[CAL_N - 1];
	float t;
	int i = interval(a, 1, &t);
	return table[i - 1] + t * (table[i] - table[i - 1]);
}

/* g(A) on the table between rows r0 and r1 (tv of the way to r1), with
 * the reflectance A g(A), not g, interpolated linearly: where the walk's
 * reflectance levels off (g ~ 1/A) a linear g would overshoot between the
 * points and A g(A) would fall again. Below the first point g is its
 * value; NaN gives 1. */
static float gain_at(const float *r0, const float *r1, float tv, float a)
{
#define ROW(k) (r0[k] + tv * (r1[k] - r0[k]))
	if (!isfinite(a))
		return 1.0f;
	if (a <= cal_albedo[1])
		return ROW(1);
	if (a >= 1.0f)
		return ROW(CAL_N - 1);
	float t;
	int i = interval(a, 2, &t);
	float q0 = cal_albedo[i - 1] * ROW(i - 1), q1 = cal_albedo[i] * ROW(i);
	return (q0 + t * (q1 - q0)) / a;
#undef ROW
}

static int is_calibration(int32_t calibration)
{
	return calibration > SSS_CALIBRATION_NONE &&
	       calibration <= SSS_CALIBRATION_CYCLES4_RANDOM_WALK;
}

/* The rows around view cosine mu and mu's place between them: g is
 * linear in mu there (clamped to the measured 0 .. 85 degrees; NaN is
 * head-on). */
static int view_rows(float mu, float *tv)
{
	*tv = 0.0f;
	if (!(mu < 1.0f))
		return 0;
	if (mu <= cal_view_cosine[VIEW_N - 1]) {
		*tv = 1.0f;
		return VIEW_N - 2;
	}
	int v = 0;
	while (cal_view_cosine[v + 1] > mu)
		v++;
	*tv = (cal_view_cosine[v] - mu) /
	      (cal_view_cosine[v] - cal_view_cosine[v + 1]);
	return v;
}

_Static_assert(VIEW_N * CAL_N == SSS__CAL_TABLE, "SSS__CAL_TABLE");

/* The material's table: its calibration's, and for plain Random Walk the
 * tables of rw4_eta and rw4_roughness around its surface blended
 * bilinearly (held beyond them; through 1.01 the roughness does not
 * count). gain_at is linear in the table, so this is the gains' blend. */
void sss__calibration_table(const sss_material *mat,
                            float table[SSS__CAL_TABLE])
{
	int32_t cal = mat->calibration;
	if (!is_calibration(cal)) {
		for (int i = 0; i < SSS__CAL_TABLE; i++)
			table[i] = 1.0f;
		return;
	}
	memcpy(table, cal_gain[cal], sizeof(float) * SSS__CAL_TABLE);
	float eta = mat->walk_ior, rough = mat->walk_roughness;
	if (cal != SSS_CALIBRATION_CYCLES4_RANDOM_WALK || !(eta > rw4_eta[0]))
		return;
	int k = 1, j = 1;
	while (k < RW4_ETA_N - 1 && rw4_eta[k] < eta)
		k++;
	while (j < RW4_ROUGH_N - 1 && rw4_roughness[j] < rough)
		j++;
	float te = fminf((eta - rw4_eta[k - 1]) /
	                 (rw4_eta[k] - rw4_eta[k - 1]), 1.0f);
	float tr = fminf(fmaxf((rough - rw4_roughness[j - 1]) /
	                       (rw4_roughness[j] - rw4_roughness[j - 1]),
	                       0.0f), 1.0f);
	const float *lo0 = &cal_gain[cal][0][0], *lo1 = lo0; /* eta k - 1 */
	if (k > 1) {
		lo0 = &rw4_gain[k - 2][j - 1][0][0];
		lo1 = &rw4_gain[k - 2][j][0][0];
	}
	const float *hi0 = &rw4_gain[k - 1][j - 1][0][0];
	const float *hi1 = &rw4_gain[k - 1][j][0][0];
	for (int i = 0; i < SSS__CAL_TABLE; i++) {
		float lo = lo0[i] + tr * (lo1[i] - lo0[i]);
		float hi = hi0[i] + tr * (hi1[i] - hi0[i]);
		table[i] = lo + te * (hi - lo);
	}
}

sss_result sss_calibration_gain(const sss_material *mat,
                                const float albedo[3], float view_cosine,
                                float gain[3])
{
	/* the material's schema says what it may hold (sss_fields.h) */
	if (!albedo || !gain || sss_material_validate(mat, NULL, 0))
		return SSS_ERR_INVALID_ARGUMENT;
	int32_t cal = mat->calibration;
	float tv, table[SSS__CAL_TABLE];
	int v = view_rows(fabsf(view_cosine), &tv);
	sss__calibration_table(mat, table);
	for (int c = 0; c < 3; c++)
		gain[c] = is_calibration(cal)
		          ? gain_at(table + v * CAL_N, table + (v + 1) * CAL_N, tv,
		                    albedo[c])
		          : 1.0f;
	return SSS_OK;
}

/* Cycles (kernel/types.h, every version from 2.7 to 5.0) renders a channel
 * whose radius is below 1e-8 with its diffuse BSDF instead of the walk: the
 * gain jumps to 1 there. On the world-lit slab of section 3 (Random Walk
 * (Skin), 4.5.15) the walk's energy is g(A) at every radius from 2e-8 to
 * 1e-2 m (A = 0.3 / 0.5 / 0.8: 0.925 / 0.960 / 0.993, within 3e-4), but on
 * the bundled scenes it is not, and the loss depends on where the object
 * is: at 1e-6 times their radius (1e-8 to 1.1e-7 m) the walk returns 0.35 -
 * 0.68 of the diffuse render's light, at 1e-4 times (1e-6 to 1.1e-5 m) 0.88
 * - 1.0; the block scene at 1e-4 times (4e-6 m) returns 0.88 / 0.93 / 0.97
 * where it stands, 0.47 / 0.51 / 0.54 moved 100 m from the world's origin.
 * A float precision limit of the walk, then: its steps come near the
 * spacing of the positions' floats (6e-8 m at 1 m, 8e-6 m at 100 m). So
 * the gain applies in full from a radius of 1e-3 (a thousand spacings up to
 * 100 m from the origin), not at all at 1e-5 and below, log-linear between
 * (every gain there made that block worse than no SSS): the output tends
 * continuously to the render without SSS as the radius vanishes. */
#define CALIBRATION_NONE_BELOW 1e-5
#define CALIBRATION_FULL_FROM 1e-3

float sss__calibration_fade(double radius)
{
	if (!(radius > CALIBRATION_NONE_BELOW))
		return 0.0f; /* also NaN */
	double f = log10(radius / CALIBRATION_NONE_BELOW) /
	           log10(CALIBRATION_FULL_FROM / CALIBRATION_NONE_BELOW);
	return f >= 1.0 ? 1.0f : (float)f;
}

int sss__calibration_needs_view(const sss_material *mat,
                                const float fade[3])
{
	return is_calibration(mat->calibration) && mat->strength > 0.0f &&
	       (fade[0] > 0.0f || fade[1] > 0.0f || fade[2] > 0.0f);
}

/* 5. Shape. Sections 1 - 4 measured flat slabs. On a convex object the
 *    walk leaves the medium sooner than in a half-space, so less of its
 *    light is absorbed (calibrate.py --part shape: a sphere of radius
 *    a = 4 cm, 128 x 64 segments, seen head-on by an orthographic camera
 *    12 cm wide under a sun along the view, 64 x 64, 256 samples; the
 *    walk's light over the diffuse lobe's in the middle 6 x 6 pixels,
 *    divided by the flat slab's under the same sun). By albedo and
 *    x = radius / a, the radius times the sphere's mean curvature 1/a:
 *    the ratio rises with x, the more the less light a slab returns
 *    (4.5.15's Random Walk (Skin) at x = 1: 2.76 at A = 0.05, 1.15 at
 *    0.5, 1.04 at 0.8), then falls once light crosses the object and
 *    leaves by its far side (x = 100: 0.30 at A = 0.5). A cylinder of
 *    radius a (mean curvature 1/(2a)) measures as the sphere at half
 *    its x within 20 %; a slab lit at 0, 28 or 60 degrees gives the
 *    same ratio at every radius. The rows are x = 0 (flat: 1) and the
 *    measured x; A = 0 is as 0.05. Blender 3.4.1 (Random Walk) for
 *    SSS_CALIBRATION_CYCLES_RANDOM_WALK, 4.5.15 for the others (5.0.1's
 *    walk measures as 4.5's in sections 1 - 4). */
static const float shape_x[] = {0.0f, 0.01f, 0.03f, 0.1f, 0.3f, 1.0f, 3.0f,
                                10.0f, 30.0f, 100.0f};
#define SHAPE_N ((int)(sizeof shape_x / sizeof *shape_x))
static const float shape_gain[][SHAPE_N][CAL_N] = {
	[SSS_CALIBRATION_CYCLES_RANDOM_WALK] = {
		/* x = 0 */
		{1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f,
		 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f},
		/* x = 0.01 */
		{1.0072f, 1.0072f, 1.0071f, 1.0071f, 1.0050f, 1.0053f, 1.0057f, 1.0076f,
		 1.0073f, 1.0068f, 1.0070f, 1.0072f, 1.0073f, 1.0072f, 1.0072f, 1.0072f},
		/* x = 0.03 */
		{1.0079f, 1.0079f, 1.0076f, 1.0076f, 1.0052f, 1.0054f, 1.0059f, 1.0080f,
		 1.0079f, 1.0079f, 1.0084f, 1.0087f, 1.0088f, 1.0088f, 1.0088f, 1.0088f},
		/* x = 0.1 */
		{1.0123f, 1.0123f, 1.0111f, 1.0110f, 1.0092f, 1.0100f, 1.0110f, 1.0140f,
		 1.0147f, 1.0154f, 1.0155f, 1.0153f, 1.0152f, 1.0152f, 1.0152f, 1.0151f},
		/* x = 0.3 */
		{1.0365f, 1.0365f, 1.0332f, 1.0314f, 1.0296f, 1.0312f, 1.0327f, 1.0340f,
		 1.0347f, 1.0340f, 1.0307f, 1.0280f, 1.0270f, 1.0269f, 1.0269f, 1.0269f},
		/* x = 1 */
		{1.1708f, 1.1708f, 1.1325f, 1.1095f, 1.1099f, 1.1037f, 1.0974f, 1.0897f,
		 1.0742f, 1.0445f, 1.0233f, 1.0020f, 0.9952f, 0.9952f, 0.9951f, 0.9951f},
		/* x = 3 */
		{1.8300f, 1.8300f, 1.5381f, 1.3671f, 1.2850f, 1.2256f, 1.1650f, 1.0988f,
		 1.0246f, 0.9428f, 0.9035f, 0.8681f, 0.8576f, 0.8576f, 0.8576f, 0.8576f},
		/* x = 10 */
		{3.3543f, 3.3543f, 2.2323f, 1.5853f, 1.2901f, 1.1076f, 0.9677f, 0.8571f,
		 0.7608f, 0.6773f, 0.6427f, 0.6129f, 0.6043f, 0.6043f, 0.6043f, 0.6043f},
		/* x = 30 */
		{4.3956f, 4.3956f, 2.4987f, 1.4761f, 1.0790f, 0.8635f, 0.7203f, 0.6162f,
		 0.5363f, 0.4719f, 0.4454f, 0.4237f, 0.4175f, 0.4175f, 0.4175f, 0.4175f},
		/* x = 100 */
		{4.7892f, 4.7892f, 2.4922f, 1.3153f, 0.9033f, 0.6936f, 0.5635f, 0.4762f,
		 0.4102f, 0.3588f, 0.3387f, 0.3218f, 0.3169f, 0.3169f, 0.3169f, 0.3169f},
	},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN] = {
		/* x = 0 */
		{1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f,
		 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f},
		/* x = 0.01 */
		{1.0154f, 1.0154f, 1.0130f, 1.0099f, 1.0098f, 1.0064f, 1.0074f, 1.0125f,
		 1.0049f, 1.0077f, 1.0143f, 1.0054f, 1.0053f, 1.0086f, 1.0086f, 1.0031f},
		/* x = 0.03 */
		{1.0610f, 1.0610f, 1.0439f, 1.0275f, 1.0212f, 1.0138f, 1.0121f, 1.0155f,
		 1.0068f, 1.0086f, 1.0156f, 1.0055f, 1.0055f, 1.0089f, 1.0089f, 1.0072f},
		/* x = 0.1 */
		{1.2684f, 1.2684f, 1.1682f, 1.1017f, 1.0717f, 1.0468f, 1.0340f, 1.0332f,
		 1.0207f, 1.0144f, 1.0197f, 1.0079f, 1.0081f, 1.0117f, 1.0116f, 1.0081f},
		/* x = 0.3 */
		{1.9094f, 1.9094f, 1.5123f, 1.2857f, 1.1967f, 1.1349f, 1.0971f, 1.0769f,
		 1.0509f, 1.0295f, 1.0297f, 1.0173f, 1.0174f, 1.0193f, 1.0193f, 1.0085f},
		/* x = 1 */
		{2.7566f, 2.7566f, 1.8424f, 1.4054f, 1.2800f, 1.2035f, 1.1513f, 1.1182f,
		 1.0891f, 1.0438f, 1.0498f, 1.0346f, 1.0339f, 1.0366f, 1.0366f, 1.0100f},
		/* x = 3 */
		{2.9191f, 2.9191f, 1.7093f, 1.1431f, 0.9914f, 0.9390f, 0.9231f, 0.9292f,
		 0.9362f, 0.9353f, 0.9785f, 1.0015f, 0.9943f, 0.9971f, 0.9971f, 1.0127f},
		/* x = 10 */
		{2.8823f, 2.8823f, 1.5254f, 0.8666f, 0.6685f, 0.5904f, 0.5613f, 0.5610f,
		 0.5906f, 0.6548f, 0.7395f, 0.8224f, 0.8114f, 0.8198f, 0.8198f, 1.0239f},
		/* x = 30 */
		{2.8487f, 2.8487f, 1.4459f, 0.7528f, 0.5344f, 0.4330f, 0.3820f, 0.3549f,
		 0.3575f, 0.3920f, 0.4564f, 0.5595f, 0.5511f, 0.5474f, 0.5474f, 1.0212f},
		/* x = 100 */
		{2.8314f, 2.8314f, 1.4140f, 0.7089f, 0.4785f, 0.3666f, 0.3032f, 0.2649f,
		 0.2466f, 0.2451f, 0.2630f, 0.3153f, 0.3103f, 0.3124f, 0.3124f, 0.8921f},
	},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK] = {
		/* x = 0 */
		{1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f,
		 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f, 1.0000f},
		/* x = 0.01 */
		{1.0106f, 1.0106f, 1.0110f, 1.0117f, 1.0099f, 1.0101f, 1.0100f, 1.0084f,
		 1.0077f, 1.0070f, 1.0087f, 1.0083f, 1.0082f, 1.0081f, 1.0081f, 1.0081f},
		/* x = 0.03 */
		{1.0105f, 1.0105f, 1.0110f, 1.0117f, 1.0099f, 1.0101f, 1.0101f, 1.0086f,
		 1.0082f, 1.0082f, 1.0102f, 1.0102f, 1.0102f, 1.0101f, 1.0101f, 1.0101f},
		/* x = 0.1 */
		{1.0118f, 1.0118f, 1.0124f, 1.0135f, 1.0125f, 1.0139f, 1.0151f, 1.0150f,
		 1.0158f, 1.0170f, 1.0200f, 1.0201f, 1.0200f, 1.0200f, 1.0200f, 1.0200f},
		/* x = 0.3 */
		{1.0270f, 1.0270f, 1.0279f, 1.0307f, 1.0320f, 1.0349f, 1.0373f, 1.0385f,
		 1.0393f, 1.0397f, 1.0385f, 1.0364f, 1.0356f, 1.0356f, 1.0356f, 1.0356f},
		/* x = 1 */
		{1.0945f, 1.0945f, 1.0945f, 1.0965f, 1.1015f, 1.1037f, 1.1033f, 1.0983f,
		 1.0833f, 1.0492f, 1.0281f, 1.0033f, 0.9954f, 0.9953f, 0.9953f, 0.9953f},
		/* x = 3 */
		{1.2490f, 1.2490f, 1.2469f, 1.2343f, 1.2315f, 1.1968f, 1.1463f, 1.0810f,
		 1.0003f, 0.9069f, 0.8658f, 0.8254f, 0.8134f, 0.8134f, 0.8134f, 0.8134f},
		/* x = 10 */
		{1.3606f, 1.3606f, 1.2988f, 1.1754f, 1.0668f, 0.9492f, 0.8384f, 0.7392f,
		 0.6479f, 0.5657f, 0.5319f, 0.5027f, 0.4942f, 0.4942f, 0.4942f, 0.4942f},
		/* x = 30 */
		{0.9205f, 0.9205f, 0.8357f, 0.6932f, 0.5825f, 0.4916f, 0.4181f, 0.3587f,
		 0.3091f, 0.2671f, 0.2510f, 0.2367f, 0.2326f, 0.2326f, 0.2326f, 0.2326f},
		/* x = 100 */
		{0.3749f, 0.3749f, 0.3303f, 0.2617f, 0.2148f, 0.1774f, 0.1487f, 0.1270f,
		 0.1088f, 0.0937f, 0.0879f, 0.0828f, 0.0813f, 0.0813f, 0.0813f, 0.0813f},
	},
};

/* 5b. Far. Once the radius is many times the object's curvature radius
 *    the walk's light spreads over the whole object and leaves it
 *    evenly, by faces the camera does not see as much as by those it
 *    does: the visible side returns what enters the object at all,
 *    less the far side's share and what is absorbed, whatever its
 *    shading (the 3.4 walk on the 8 cm sphere at 5 m was 0.56 of the
 *    diffuse render in red where ours, lit side kept, was 1.04). The
 *    same sphere runs as section 5, over every pixel of its visible side
 *    instead of the middle (calibrate.py --part shape, gain_whole: the
 *    walk over SSS off there, over the flat slab's), at x = 10, 30,
 *    100 and 300; beyond, as 300. It is applied per material at the
 *    median x over its pixels (sss_auto.c: the object's scale, not an
 *    edge's), rising from none at x = 10 to all of it at x = 30 (log x),
 *    in place of the per-pixel shape term. */
static const float far_x[] = {10.0f, 30.0f, 100.0f, 300.0f};
#define FAR_N ((int)(sizeof far_x / sizeof *far_x))
static const float far_gain[][FAR_N][CAL_N] = {
	[SSS_CALIBRATION_CYCLES_RANDOM_WALK] = {
		/* x = 10 */
		{7.1778f, 7.1778f, 3.6446f, 1.8703f, 1.3133f, 1.0571f, 0.9135f, 0.8476f,
		 0.8047f, 0.8055f, 0.8411f, 0.9047f, 0.8959f, 0.8968f, 0.8972f, 1.0260f},
		/* x = 30 */
		{7.3734f, 7.3734f, 3.7009f, 1.8494f, 1.2575f, 0.9763f, 0.8116f, 0.7201f,
		 0.6562f, 0.6323f, 0.6557f, 0.7185f, 0.7106f, 0.7131f, 0.7134f, 1.0318f},
		/* x = 100 */
		{7.4453f, 7.4453f, 3.7219f, 1.8416f, 1.2347f, 0.9430f, 0.7680f, 0.6644f,
		 0.5857f, 0.5345f, 0.5277f, 0.5529f, 0.5469f, 0.5479f, 0.5483f, 0.9435f},
		/* x = 300 */
		{7.4659f, 7.4659f, 3.7273f, 1.8385f, 1.2284f, 0.9335f, 0.7556f, 0.6469f,
		 0.5629f, 0.5004f, 0.4808f, 0.4811f, 0.4760f, 0.4764f, 0.4768f, 0.7771f},
	},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN] = {
		/* x = 10 */
		{4.2049f, 4.2049f, 2.1483f, 1.1460f, 0.8339f, 0.7032f, 0.6445f, 0.6194f,
		 0.6157f, 0.6799f, 0.7337f, 0.8252f, 0.8145f, 0.8142f, 0.8142f, 1.0318f},
		/* x = 30 */
		{4.2737f, 4.2737f, 2.1276f, 1.0714f, 0.7292f, 0.5732f, 0.4901f, 0.4412f,
		 0.4161f, 0.4450f, 0.4872f, 0.5793f, 0.5708f, 0.5715f, 0.5715f, 1.0277f},
		/* x = 100 */
		{4.2922f, 4.2922f, 2.1150f, 1.0390f, 0.6892f, 0.5222f, 0.4273f, 0.3635f,
		 0.3208f, 0.3116f, 0.3203f, 0.3642f, 0.3586f, 0.3597f, 0.3597f, 0.8959f},
		/* x = 300 */
		{4.2997f, 4.2997f, 2.1123f, 1.0299f, 0.6758f, 0.5056f, 0.4069f, 0.3396f,
		 0.2907f, 0.2663f, 0.2574f, 0.2684f, 0.2642f, 0.2649f, 0.2649f, 0.6659f},
	},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK] = {
		/* x = 10 */
		{1.2497f, 1.2497f, 1.1883f, 1.0634f, 0.9349f, 0.8309f, 0.7337f, 0.6428f,
		 0.5649f, 0.4946f, 0.4657f, 0.4413f, 0.4343f, 0.4343f, 0.4343f, 0.4343f},
		/* x = 30 */
		{0.7872f, 0.7872f, 0.7146f, 0.5899f, 0.4875f, 0.4128f, 0.3519f, 0.3007f,
		 0.2599f, 0.2253f, 0.2113f, 0.1999f, 0.1966f, 0.1966f, 0.1966f, 0.1966f},
		/* x = 100 */
		{0.3162f, 0.3162f, 0.2789f, 0.2204f, 0.1762f, 0.1462f, 0.1230f, 0.1041f,
		 0.0895f, 0.0773f, 0.0725f, 0.0685f, 0.0674f, 0.0674f, 0.0674f, 0.0674f},
		/* x = 300 */
		{0.1165f, 0.1165f, 0.1018f, 0.0794f, 0.0628f, 0.0518f, 0.0434f, 0.0366f,
		 0.0314f, 0.0271f, 0.0254f, 0.0240f, 0.0236f, 0.0236f, 0.0236f, 0.0236f},
	},
};

float sss__far_gain(int32_t calibration, float albedo, float x,
                    float *weight)
{
	*weight = 0.0f;
	if (!is_calibration(calibration) || !(x > far_x[0]) ||
	    !isfinite(albedo))
		return 1.0f;
	*weight = x >= 3.0f * far_x[0] ? 1.0f
	          : logf(x / far_x[0]) / logf(3.0f);
	int j = 1;
	float tx = 1.0f;
	if (x >= far_x[FAR_N - 1]) {
		j = FAR_N - 1;
	} else {
		while (far_x[j] < x)
			j++;
		tx = logf(x / far_x[j - 1]) / logf(far_x[j] / far_x[j - 1]);
	}
	float a = albedo <= cal_albedo[1] ? cal_albedo[1]
	          : albedo >= 1.0f ? 1.0f : albedo;
	float ta = 0.0f;
	int i = a <= cal_albedo[1] ? 2 : interval(a, 2, &ta);
	const float *r0 = far_gain[calibration][j - 1];
	const float *r1 = far_gain[calibration][j];
	float g0 = r0[i - 1] + ta * (r0[i] - r0[i - 1]);
	float g1 = r1[i - 1] + ta * (r1[i] - r1[i - 1]);
	return g0 + tx * (g1 - g0);
}

static int has_shape(int32_t calibration)
{
	return is_calibration(calibration);
}

int sss__calibration_needs_shape(const sss_material *mat,
                                 const float fade[3])
{
	return has_shape(mat->calibration) && mat->kind == SSS_PROFILE_BURLEY &&
	       sss__calibration_needs_view(mat, fade);
}

float sss__shape_gain(int32_t calibration, float albedo, float x)
{
	if (!has_shape(calibration) || !(x > 0.0f) || !isfinite(albedo))
		return 1.0f;
	/* x: linear from 0 to the first point, then linear in log x */
	int j = 1;
	float tx;
	if (x >= shape_x[SHAPE_N - 1]) {
		j = SHAPE_N - 1;
		tx = 1.0f;
	} else {
		while (shape_x[j] < x)
			j++;
		tx = j == 1 ? x / shape_x[1]
		            : logf(x / shape_x[j - 1]) /
		              logf(shape_x[j] / shape_x[j - 1]);
	}
	float a = albedo <= cal_albedo[1] ? cal_albedo[1]
	          : albedo >= 1.0f ? 1.0f : albedo;
	float ta = 0.0f;
	int i = a <= cal_albedo[1] ? 2 : interval(a, 2, &ta);
	const float *r0 = shape_gain[calibration][j - 1];
	const float *r1 = shape_gain[calibration][j];
	float g0 = r0[i - 1] + ta * (r0[i] - r0[i - 1]);
	float g1 = r1[i - 1] + ta * (r1[i] - r1[i - 1]);
	return g0 + tx * (g1 - g0);
}

void sss__calibration_apply(const sss_material *mat, const float *table,
                            const float fade[3],
                            float view_cosine, const float *shape,
                            const float *far, const float *diff_col,
                            float *light)
{
	float f[3];
	sss__calibration_factors(mat, table, fade, view_cosine, shape, far,
	                         diff_col, f);
	for (int c = 0; c < 3; c++)
		light[c] *= f[c];
}

void sss__calibration_factors(const sss_material *mat, const float *table,
                              const float fade[3], float view_cosine,
                              const float *shape, const float *far,
                              const float *diff_col, float factor[3])
{
	factor[0] = factor[1] = factor[2] = 1.0f;
	if (!is_calibration(mat->calibration))
		return;
	float s = mat->strength, tv;
	int v = view_rows(view_cosine, &tv);
	for (int c = 0; c < 3; c++) {
		float m = (mat->kind == SSS_PROFILE_JIMENEZ
		           ? s * mat->jimenez_strength[c] : s) * fade[c];
		if (!(m > 0.0f))
			continue;
		float g = gain_at(table + v * CAL_N, table + (v + 1) * CAL_N, tv,
		                  diff_col[c]);
		if (shape) {
			/* The table was measured head-on; seen at an angle the
			 * flat gain g(A, mu) already holds the walk's excess near a
			 * silhouette, so a rise counts times the view cosine (on
			 * the 8 cm sphere at 3x the rims were 5 - 10 % too bright
			 * without). Its fall (light crossing the object and leaving
			 * by the far side) is the object's thickness, not the
			 * curvature of its visible surface: read from curvature it
			 * darkened a thick block's edges (block at 100x: 0.52 ->
			 * 0.72 of the error without SSS) and the sphere at 10x, so
			 * it is not applied. */
			float sg = sss__shape_gain(mat->calibration, diff_col[c],
			                           shape[c]);
			float local = sg > 1.0f ? 1.0f + view_cosine * (sg - 1.0f)
			                        : 1.0f;
			float w = 0.0f;
			float whole = far ? sss__far_gain(mat->calibration,
			                                  diff_col[c], far[c], &w)
			                  : 1.0f;
			g *= (1.0f - w) * local + w * whole;
		}
		factor[c] = 1.0f + m * (g - 1.0f);
	}
}

/* 6. Crease. A sharp convex edge: light that enters one face within a
 *    few mean free paths of it leaves through the other (calibrate.py
 *    --part crease: the box's top front edge seen at 45 degrees by an
 *    orthographic camera 0.2 m wide, 96 x 96, 256 samples, a sun at
 *    normal incidence on the front face grazing the top face; the walk
 *    against the SSS-off render scattered by the separable method with
 *    this calibration and no crease term). On the unlit face, at
 *    distance t from the edge, the walk exceeds that by kappa F(t) of
 *    the lit face's scattered light, F the mass of Burley's 1-D marginal
 *    beyond t for d = gamma r (r: the radius); by albedo, kappa and gamma
 *    fitted per channel at r = 3 cm over the unlit face's profile (RMS
 *    0.001 - 0.005 of the lit face above A = 0.3, 0.04 at A = 0.05, where
 *    the walk's first unlit pixel is 5 times the lit face). For 4.5.15's
 *    Random Walk (Skin), at 2 and 6 cm they agree within 8 % above
 *    A = 0.5 with gamma 0.15 - 0.16: the profile follows the radius. Its
 *    plain Random Walk (SSS_CALIBRATION_CYCLES4_RANDOM_WALK) keeps the
 *    light much closer to the edge below A = 0.8 (gamma 0.025 - 0.13):
 *    its rows were measured with a camera 0.1 m wide at 192 x 192, so
 *    that d spans pixels, through Principled's default surface (index
 *    1.5, roughness 0.5: --specular 0.5; see rw4_gain), where it carries
 *    a tenth to a half more than through 1.01 (gain kappa at A = 1 / 0.05).
 *    Blender 3.4.1's Random Walk for SSS_CALIBRATION_CYCLES_RANDOM_WALK
 *    (96 x 96 over 0.2 m).
 *    A = 0 is as 0.05. At exactly A = 1 both Random Walk (Skin) of 4.5
 *    and 3.4's Random Walk measured no excess (under 0.003 at 3 and
 *    5 cm), and plain Random Walk the row it has. kappa is interpolated
 *    as A kappa, which is nearly flat at low albedo (Skin: 0.50 - 0.57
 *    up to A = 0.6). Checked at r = 5 cm (Skin): the walk's excess on
 *    the unlit face, RMS 0.02 - 0.23 of the lit face from A = 0.99 down
 *    to 0.3 (1.55 at 0.05), is 0.003 - 0.012 with the term (0.09).
 *    The blur's own share across the edge depends on the view (the
 *    unlit face seen head-on takes a fifth of what it takes at 70
 *    degrees), the walk's does not: so the separable blur stops at
 *    creases (for every calibration with a crease_loss_* row below) and
 *    the rows here are fitted over that stopped blur (calibrate.py
 *    --part crease, its `stopped` column; fit_crease.py), the whole of
 *    what crosses, at r = 3 cm and 45 degrees. Checked at 4 cm from 20,
 *    45 and 70 degrees (docs/calibration.md): within 5 cm of the edge
 *    the RMS against each walk fell 2 - 6 times from the rows fitted
 *    over the crossing blur. */
static const float crease_kappa[][CAL_N] = {
	[SSS_CALIBRATION_CYCLES_RANDOM_WALK] = {
		21.074f, 21.074f, 11.102f, 6.042f, 4.288f, 3.377f, 2.785f, 2.367f,
		2.002f, 1.635f, 1.438f, 1.168f, 1.173f, 1.158f, 1.157f, 0.0f},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN] = {
		11.897f, 11.897f, 6.690f, 4.010f, 3.088f, 2.558f, 2.195f, 1.897f,
		1.644f, 1.426f, 1.204f, 1.037f, 1.004f, 1.018f, 1.018f, 0.0f},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK] = {
		2.464f, 2.464f, 2.298f, 2.217f, 2.030f, 1.991f, 1.796f, 1.657f,
		1.524f, 1.375f, 1.255f, 1.195f, 1.131f, 1.120f, 1.117f, 1.114f},
};
static const float crease_gamma[][CAL_N] = {
	[SSS_CALIBRATION_CYCLES_RANDOM_WALK] = {
		0.41f, 0.41f, 0.37f, 0.31f, 0.26f, 0.22f, 0.19f, 0.16f,
		0.14f, 0.11f, 0.085f, 0.065f, 0.065f, 0.065f, 0.065f, 0.065f},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN] = {
		0.41f, 0.41f, 0.37f, 0.31f, 0.26f, 0.22f, 0.19f, 0.17f,
		0.15f, 0.11f, 0.095f, 0.065f, 0.07f, 0.07f, 0.07f, 0.07f},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK] = {
		0.025f, 0.025f, 0.03f, 0.035f, 0.045f, 0.05f, 0.065f, 0.08f,
		0.10f, 0.13f, 0.16f, 0.18f, 0.19f, 0.19f, 0.19f, 0.19f},
};
#define CREASE_ROWS ((int32_t)(sizeof crease_kappa / sizeof *crease_kappa))
/* With the blur stopped at creases (the calibrations that have these
 * rows): what the lit face loses near the edge, kappa F(t) of its own
 * light, fitted like the gain on the lit face's profile. */
static const float crease_loss_kappa[][CAL_N] = {
	[SSS_CALIBRATION_CYCLES_RANDOM_WALK] = {
		1.539f, 1.539f, 1.480f, 1.465f, 1.521f, 1.532f, 1.515f, 1.435f,
		1.410f, 1.292f, 1.108f, 0.940f, 1.000f, 0.997f, 0.998f, 0.0f},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN] = {
		4.499f, 4.499f, 2.603f, 1.677f, 1.403f, 1.254f, 1.136f, 1.091f,
		1.063f, 0.936f, 0.877f, 0.756f, 0.779f, 0.728f, 0.728f, 0.0f},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK] = {
		0.292f, 0.292f, 0.326f, 0.420f, 0.561f, 0.678f, 0.790f, 0.904f,
		0.998f, 1.017f, 1.035f, 1.022f, 0.877f, 0.834f, 0.818f, 0.814f},
};
static const float crease_loss_gamma[][CAL_N] = {
	[SSS_CALIBRATION_CYCLES_RANDOM_WALK] = {
		0.31f, 0.31f, 0.29f, 0.25f, 0.21f, 0.18f, 0.16f, 0.16f,
		0.13f, 0.10f, 0.085f, 0.055f, 0.05f, 0.055f, 0.055f, 0.055f},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN] = {
		0.34f, 0.34f, 0.35f, 0.34f, 0.31f, 0.27f, 0.24f, 0.21f,
		0.17f, 0.12f, 0.11f, 0.07f, 0.07f, 0.08f, 0.08f, 0.08f},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK] = {
		0.16f, 0.16f, 0.15f, 0.13f, 0.10f, 0.095f, 0.095f, 0.095f,
		0.10f, 0.12f, 0.13f, 0.15f, 0.26f, 0.31f, 0.33f, 0.34f},
};

static void crease_row(const float (*kt)[CAL_N], const float (*gt)[CAL_N],
                       int32_t calibration, float albedo, float *kappa,
                       float *gamma)
{
	*kappa = *gamma = 0.0f;
	if (!is_calibration(calibration) || calibration >= CREASE_ROWS ||
	    !(gt[calibration][1] > 0.0f) || !isfinite(albedo))
		return;
	const float *k = kt[calibration];
	float a = albedo < cal_albedo[1] ? cal_albedo[1]
	          : albedo > 1.0f ? 1.0f : albedo, t;
	int i = interval(a, 2, &t);
	if (a <= cal_albedo[1])
		i = 2, t = 0.0f;
	float q0 = cal_albedo[i - 1] * k[i - 1], q1 = cal_albedo[i] * k[i];
	*kappa = (q0 + t * (q1 - q0)) / a;
	*gamma = lerp_table(gt[calibration], a);
}

void sss__crease_params(int32_t calibration, float albedo, float *kappa,
                        float *gamma)
{
	crease_row(crease_kappa, crease_gamma, calibration, albedo, kappa,
	           gamma);
}

void sss__crease_loss_params(int32_t calibration, float albedo, float *kappa,
                             float *gamma)
{
	crease_row(crease_loss_kappa, crease_loss_gamma, calibration, albedo,
	           kappa, gamma);
}

/* Cycles 3.4, bssrdf.h: Jensen's dipole reflectance with a boundary of
 * relative index eta, inverted for a' (Cycles bisects 12 times; 48 steps
 * here: the measured widths follow the exact inverse better). */
static double dipole_rd(double a, double four_thirds_a)
{
	double s = sqrt(3.0 * (1.0 - a));
	return 0.5 * a * (1.0 + exp(-four_thirds_a * s)) * exp(-s);
}

/* Below this d / radius the measured random walk stops narrowing
 * (A = 0.9 .. 0.99: 0.032 - 0.034). */
#define CYCLES_RW_MIN_D 0.032

double sss__cycles_rw_mfp_over_radius(double albedo)
{
	const double eta = 1.4; /* Principled's default Subsurface IOR */
	double f_dr = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
	double four_thirds_a = 4.0 / 3.0 * (1.0 + f_dr) / (1.0 - f_dr);
	double a = albedo, alpha;
	if (!(a >= 1e-4))
		alpha = 0.0; /* also NaN: validation refuses it before here */
	else if (a >= 0.995)
		alpha = 0.999999; /* Cycles' own limit */
	else {
		double lo = 0.0, hi = 1.0;
		for (int i = 0; i < 48; i++) {
			double mid = 0.5 * (lo + hi);
			if (dipole_rd(mid, four_thirds_a) < a)
				lo = mid;
			else
				hi = mid;
		}
		alpha = 0.5 * (lo + hi);
	}
	return sqrt(3.0 * (1.0 - alpha));
}

double sss__cycles_rw_d_over_radius(double albedo)
{
	double a = albedo;
	double s = 1.9 - a + 3.5 * (a - 0.8) * (a - 0.8);
	double d = sss__cycles_rw_mfp_over_radius(a) / s;
	if (a < 0.995 && d < CYCLES_RW_MIN_D)
		d = CYCLES_RW_MIN_D;
	return d;
}

/* Section 3: Cycles 4.x/5.x's Random Walk, d / radius at cal_albedo
 * (A = 0 as at 0.05: the fit cannot go below a pixel there). */
static const float cycles4_rw_d[CAL_N] = {
	0.0171f, 0.0171f, 0.0192f, 0.0251f, 0.0304f, 0.0369f, 0.0447f, 0.0541f,
	0.0656f, 0.0825f, 0.0891f, 0.100f, 0.1039f, 0.1039f, 0.1039f, 0.1039f};

double sss__cycles4_rw_d_over_radius(double albedo)
{
	return lerp_table(cycles4_rw_d, (float)albedo);
}
