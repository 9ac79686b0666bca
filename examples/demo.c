/* demo.c - libsss on a small synthetic render, written as PNGs.
 *
 *   build/sss-demo OUTDIR
 *
 * Ray-casts two spheres (skin-like and jade-like Burley) before a grey
 * wall into the passes Blender writes: a hard key light from the upper
 * left, a little ambient, the sharp shadow of an off-screen pole and thin
 * dark grid lines in DiffCol. libsss runs without and with scattering;
 * OUTDIR/demo.png shows no SSS | SSS | 4x |difference|, demo_crop.png a 3x
 * zoom of the left sphere's terminator and pole shadow, before and after.
 */
#include "sss.h"
#include "synth.h"

#include <errno.h>
#include <math.h>
#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define W 480
#define H 270
#define PI 3.14159265358979323846

/* View space: x right, y up, z = planar depth along the view axis, so a
 * camera ray through a pixel is t * (X, Y, 1) and its depth is simply t. */
typedef struct sphere {
	double c[3], r;
	int index;
	float albedo[3];
} sphere;

static const sphere spheres[2] = {
	{{-0.33, -0.02, 2.0}, 0.25, 1, {0.85f, 0.62f, 0.52f}}, /* skin */
	{{0.33, -0.02, 2.0}, 0.25, 2, {0.50f, 0.78f, 0.58f}},  /* jade */
};
/* A vertical pole, off-screen left and in front, whose shadow slab crosses
 * the lit side of the left sphere: a hard light edge to be softened. */
static const double pole_x = -1.355, pole_z = 1.547, pole_r = 0.008;
static const double wall_z = 3.5; /* wall spans |x| < 1, -0.6 < y < 0.45 */

static double dot3(const double *a, const double *b)
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void normalize3(double *v)
{
	double n = sqrt(dot3(v, v));
	v[0] /= n, v[1] /= n, v[2] /= n;
}

/* Nearest t > eps with o + t d on the sphere, or -1. */
static double hit_sphere(const sphere *s, const double *o, const double *d)
{
	double oc[3] = {o[0] - s->c[0], o[1] - s->c[1], o[2] - s->c[2]};
	double a = dot3(d, d), b = dot3(d, oc), c = dot3(oc, oc) - s->r * s->r;
	double disc = b * b - a * c;
	if (disc < 0)
		return -1;
	double t = (-b - sqrt(disc)) / a;
	return t > 1e-6 ? t : -1;
}

/* Is the light (direction l) blocked from point p by a sphere or the pole? */
static int shadowed(const double *p, const double *l)
{
	for (int i = 0; i < 2; i++)
		if (hit_sphere(&spheres[i], p, l) > 0)
			return 1;
	/* The pole is an infinite vertical cylinder: intersect in x-z only. */
	double ox = p[0] - pole_x, oz = p[2] - pole_z;
	double a = l[0] * l[0] + l[2] * l[2], b = ox * l[0] + oz * l[2];
	double disc = b * b - a * (ox * ox + oz * oz - pole_r * pole_r);
	return disc >= 0 && -b + sqrt(disc) > 0;
}

/* Thin dark latitude/longitude lines every 15 degrees: texture detail
 * that post-scatter texturing must keep sharp. */
static float grid(const double *n)
{
	double lat = asin(n[1]) * 180 / PI, lon = atan2(n[0], -n[2]) * 180 / PI;
	double dl = fabs(lat - 15 * floor(lat / 15 + 0.5));
	double dn = fabs(lon - 15 * floor(lon / 15 + 0.5)) * cos(lat * PI / 180);
	return dl < 0.8 || dn < 0.8 ? 0.3f : 1.0f;
}

/* Ray-casts the scene into the passes of s. */
static void render(synth *s, const sss_camera *cam)
{
	/* Pixel size at depth 1 (fit AUTO on a landscape image: sensor width
	 * spans the width); pixel centres at x + 0.5 as in Blender. */
	double pix = cam->sensor_width_mm / cam->lens_mm / W;
	double l[3] = {-0.85, 0.4, -0.2}; /* towards the key light */
	normalize3(l);
	const double key = 1.2, shininess = 200.0, o[3] = {0, 0, 0};
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			size_t i = (size_t)y * W + x;
			double d[3] = {(x + 0.5 - 0.5 * W) * pix, (0.5 * H - y - 0.5) * pix,
			               1.0};
			double t = -1, n[3] = {0, 0, -1}; /* the wall faces the camera */
			const sphere *hit = NULL;
			for (int k = 0; k < 2; k++) {
				double tk = hit_sphere(&spheres[k], o, d);
				if (tk > 0 && (t < 0 || tk < t))
					t = tk, hit = &spheres[k];
			}
			if (!hit && fabs(wall_z * d[0]) < 1.0 && wall_z * d[1] > -0.6 &&
			    wall_z * d[1] < 0.45)
				t = wall_z;
			if (t < 0) { /* background: only Env, alpha 0 */
				float g = 0.02f + 0.03f * (float)(H - y) / H;
				s->env[3 * i] = g, s->env[3 * i + 1] = g;
				s->env[3 * i + 2] = 1.4f * g;
				s->combined[4 * i + 3] = 0.0f;
				continue;
			}
			double p[3] = {t * d[0], t * d[1], t};
			for (int c = 0; hit && c < 3; c++)
				n[c] = (p[c] - hit->c[c]) / hit->r;
			s->depth[i] = (float)t; /* planar view Z, what Blender writes */
			s->index[i] = (float)(hit ? hit->index : 3);
			double nl = dot3(n, l);
			/* Lambert N.L clamped at 0: the terminator; hard shadows. */
			double vis = nl > 0 && !shadowed(p, l) ? 1.0 : 0.0;
			double direct = key * vis * (nl > 0 ? nl : 0);
			double ambient = 0.03 + 0.015 * n[1];
			/* Normalised Blinn-Phong highlight, seen through GlossCol. */
			double v[3] = {-p[0], -p[1], -p[2]}, h[3];
			normalize3(v);
			for (int c = 0; c < 3; c++)
				h[c] = l[c] + v[c];
			normalize3(h);
			double nh = dot3(n, h) > 0 ? dot3(n, h) : 0;
			double spec = direct * (shininess + 8) / (8 * PI) *
			              pow(nh, shininess);
			float tex = hit ? grid(n) : 1.0f;
			for (int c = 0; c < 3; c++) {
				s->diff_dir[3 * i + c] = (float)direct;
				s->diff_ind[3 * i + c] = (float)ambient;
				s->diff_col[3 * i + c] = hit ? hit->albedo[c] * tex : 0.5f;
				s->gloss_dir[3 * i + c] = hit ? (float)spec : 0.0f;
				s->gloss_col[3 * i + c] = hit ? 0.04f : 0.0f;
			}
			s->combined[4 * i + 3] = 1.0f; /* only its alpha is read */
		}
}

/* Runs sss_apply into out (RGB); prints the library's message on error. */
static int apply(const sss_passes *p, const sss_camera *cam,
                 const sss_material *mats, int n, const sss_options *opt,
                 float *out, double *ms)
{
	char err[256] = "";
	sss_image im = synth_view(out, W, H, 3);
	struct timespec t0, t1;
	clock_gettime(CLOCK_MONOTONIC, &t0);
	sss_result r = sss_apply(p, cam, mats, n, opt, &im, NULL, err, sizeof err);
	clock_gettime(CLOCK_MONOTONIC, &t1);
	*ms = (t1.tv_sec - t0.tv_sec) * 1e3 + (t1.tv_nsec - t0.tv_nsec) * 1e-6;
	if (r != SSS_OK)
		fprintf(stderr, "demo: sss_apply: %s: %s\n", sss_status_string(r),
		        err);
	return r == SSS_OK ? 0 : -1;
}

/* Simple display transform: clamp to [0, 1], sRGB OETF, 8 bits. */
static unsigned char to8(float v)
{
	v = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; /* NaN -> 0 */
	double e = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055;
	return (unsigned char)(e * 255.0 + 0.5);
}

/* Writes an 8-bit RGB PNG atomically: a temporary file in the same folder,
 * renamed over the target only once it is complete and closed. */
static int write_png(const char *path, const unsigned char *rgb, int w, int h)
{
	char tmp[4096];
	snprintf(tmp, sizeof tmp, "%s.tmp-%ld", path, (long)getpid());
	FILE *f = fopen(tmp, "wb");
	if (!f) {
		fprintf(stderr, "demo: %s: %s\n", tmp, strerror(errno));
		return -1;
	}
	png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL,
	                                          NULL, NULL);
	png_infop info = png ? png_create_info_struct(png) : NULL;
	if (!png || !info)
		goto fail;
	if (setjmp(png_jmpbuf(png))) /* libpng has printed why */
		goto fail;
	png_init_io(png, f);
	png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, 8,
	             PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
	             PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
	png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
	png_write_info(png, info);
	for (int y = 0; y < h; y++)
		png_write_row(png, rgb + (size_t)y * w * 3);
	png_write_end(png, info);
	png_destroy_write_struct(&png, &info);
	if (fclose(f) == 0 && rename(tmp, path) == 0)
		return 0;
	fprintf(stderr, "demo: %s: %s\n", path, strerror(errno));
	remove(tmp);
	return -1;
fail: /* png, info and f are not changed after setjmp: safe to use here */
	png_destroy_write_struct(&png, &info);
	fclose(f);
	remove(tmp); /* nothing half-written stays behind */
	fprintf(stderr, "demo: cannot write %s\n", path);
	return -1;
}

/* Copies a (cw x ch at x0, y0) region of a float RGB image, tonemapped and
 * zoomed `zoom` times (nearest), into an 8-bit canvas at (dx, 0). */
static void blit(unsigned char *dst, int dst_w, int dx, const float *src,
                 int x0, int y0, int cw, int ch, int zoom, float gain)
{
	for (int y = 0; y < ch * zoom; y++)
		for (int x = 0; x < cw * zoom; x++)
			for (int c = 0; c < 3; c++) {
				size_t s = 3 * ((size_t)(y0 + y / zoom) * W + x0 + x / zoom);
				dst[3 * ((size_t)y * dst_w + dx + x) + c] = to8(gain * src[s + c]);
			}
}

/* mkdir -p: creates every missing folder on the path. */
static int make_dirs(const char *path)
{
	char buf[4096];
	snprintf(buf, sizeof buf, "%s", path);
	for (char *q = buf + 1;; q++)
		if (*q == '/' || *q == '\0') {
			char saved = *q;
			*q = '\0';
			if (mkdir(buf, 0777) != 0 && errno != EEXIST) {
				fprintf(stderr, "demo: mkdir %s: %s\n", buf, strerror(errno));
				return -1;
			}
			if ((*q = saved) == '\0')
				return 0;
		}
}

int main(int argc, char **argv)
{
	if (argc != 2 || strlen(argv[1]) > 3000) {
		fprintf(stderr, "usage: %s OUTDIR\n", argv[0]);
		return 2;
	}
	const char *outdir = argv[1];
	if (make_dirs(outdir))
		return 1;

	sss_camera cam;
	sss_camera_default(&cam); /* 50 mm lens, 36 mm sensor, fit AUTO */
	synth *s = synth_new(W, H);
	render(s, &cam);
	sss_passes passes = synth_passes(s);

	/* Burley radii in metres (Subsurface Radius), ~15x real skin (jade: a
	 * guess) so that the kernel spans many pixels at 2 m: red reaches
	 * furthest in skin, green in jade. Index 3 (the wall) does not scatter.
	 * Expected kernel half-width = support (m) x pixels per metre at the
	 * spheres' depth; Burley's support is proportional to each radius. */
	static const float radius[2][3] = {{0.054f, 0.018f, 0.009f},
	                                   {0.016f, 0.035f, 0.022f}};
	static const char *const names[2] = {"skin", "jade"};
	double ppm = W * cam.lens_mm / cam.sensor_width_mm / spheres[0].c[2];
	sss_material mats[3];
	for (int m = 0; m < 3; m++) {
		sss_material_default(&mats[m], m < 2 ? SSS_PROFILE_BURLEY
		                                     : SSS_PROFILE_NONE);
		mats[m].pass_index = m + 1;
		if (m == 2)
			break;
		memcpy(mats[m].radius, radius[m], sizeof radius[m]);
		double sup, px[3];
		sss_result r = sss_material_support(&mats[m], &sup);
		if (r != SSS_OK) {
			fprintf(stderr, "demo: %s\n", sss_status_string(r));
			return 1;
		}
		float rmax = fmaxf(radius[m][0], fmaxf(radius[m][1], radius[m][2]));
		for (int c = 0; c < 3; c++)
			px[c] = sup * ppm * radius[m][c] / rmax;
		printf("demo: material %d (%s): support %.1f mm = %.1f px at %.1f m"
		       " (R %.1f, G %.1f, B %.1f px)\n", m + 1, names[m], sup * 1e3,
		       sup * ppm, spheres[0].c[2], px[0], px[1], px[2]);
	}

	size_t n = (size_t)W * H;
	float *plain = malloc(3 * n * sizeof *plain);
	float *sss = malloc(3 * n * sizeof *sss);
	float *diff = malloc(3 * n * sizeof *diff);
	unsigned char *img = calloc((size_t)3 * (3 * W) * H, 1);
	const int cx = 95, cy = 55, cw = 100, chh = 100, zoom = 3;
	unsigned char *crop = calloc((size_t)3 * (2 * cw * zoom) * chh * zoom, 1);
	if (!plain || !sss || !diff || !img || !crop) {
		fprintf(stderr, "demo: out of memory\n");
		return 1;
	}

	sss_options off, on;
	sss_options_default(&off);
	off.radius_scale = 0.0f; /* no scattering: the passes recombined */
	sss_options_default(&on); /* separable, default taps, all cores */
	double ms_off, ms_on;
	if (apply(&passes, &cam, mats, 3, &off, plain, &ms_off) ||
	    apply(&passes, &cam, mats, 3, &on, sss, &ms_on))
		return 1;

	/* Energy check: scattering redistributes light, so the means should
	 * agree closely; the difference should sit at light edges. */
	double mean[2][3] = {{0}}, maxd = 0, outside = 0;
	size_t bad = 0, at = 0;
	for (size_t i = 0; i < 3 * n; i++) {
		mean[0][i % 3] += plain[i] / n;
		mean[1][i % 3] += sss[i] / n;
		diff[i] = fabsf(sss[i] - plain[i]);
		bad += !isfinite(sss[i]);
		if (diff[i] > maxd)
			maxd = diff[i], at = i / 3;
		/* Wall and background must pass through untouched. */
		if (s->index[i / 3] != 1 && s->index[i / 3] != 2 && diff[i] > outside)
			outside = diff[i];
	}
	printf("demo: separable SSS on %dx%d took %.2f ms (plain recombine "
	       "%.2f ms)\n", W, H, ms_on, ms_off);
	for (int c = 0; c < 3; c++)
		mean[1][c] = 100 * (mean[1][c] - mean[0][c]) / mean[0][c];
	printf("demo: image mean RGB %.4f %.4f %.4f; with SSS %+.3f%% %+.3f%% "
	       "%+.3f%%\n", mean[0][0], mean[0][1], mean[0][2], mean[1][0],
	       mean[1][1], mean[1][2]);
	printf("demo: max |difference| %.4f at pixel (%zu, %zu); off the "
	       "spheres %g; %zu non-finite values\n", maxd, at % W, at / W,
	       outside, bad);

	blit(img, 3 * W, 0, plain, 0, 0, W, H, 1, 1.0f);
	blit(img, 3 * W, W, sss, 0, 0, W, H, 1, 1.0f);
	blit(img, 3 * W, 2 * W, diff, 0, 0, W, H, 1, 4.0f);
	blit(crop, 2 * cw * zoom, 0, plain, cx, cy, cw, chh, zoom, 1.0f);
	blit(crop, 2 * cw * zoom, cw * zoom, sss, cx, cy, cw, chh, zoom, 1.0f);

	char path[2][4096];
	snprintf(path[0], sizeof path[0], "%s/demo.png", outdir);
	snprintf(path[1], sizeof path[1], "%s/demo_crop.png", outdir);
	if (write_png(path[0], img, 3 * W, H) ||
	    write_png(path[1], crop, 2 * cw * zoom, chh * zoom))
		return 1;
	printf("demo: wrote %s (no SSS | SSS | difference x4)\n"
	       "demo: wrote %s (left sphere's terminator and pole shadow, %dx: "
	       "no SSS | SSS)\n", path[0], path[1], zoom);

	free(plain), free(sss), free(diff), free(img), free(crop);
	synth_free(s);
	return 0;
}
