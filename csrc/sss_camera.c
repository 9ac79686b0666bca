/* sss_camera.c - Blender's camera model: pixels <-> view-space positions.
 *
 * Follows BKE_camera_params_compute_viewplane (Blender 3.x): the sensor
 * (or ortho scale) spans the image's larger side after pixel aspect, unless
 * the sensor fit says which side; lens shift moves the principal point by
 * a fraction of that side. Depth is planar view Z, so a pixel's position
 * is ((u - cx) z / fx, (cy - v) z / fy, z) for perspective cameras.
 */
#include "sss_camera_fields.h"
#include "sss_internal.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

/* The camera's schema (sss_camera_fields.h) as data. */
typedef struct field {
	const char *member;
	int32_t type; /* sss_field_type: SSS_FIELD_ENUM or SSS_FIELD_DOUBLE */
	int32_t when;
	size_t offset;
	double lo, hi;
	int32_t lo_open;
	const sss__name_value *names;
	int32_t name_count;
} field;

#define TYPE_ENUM SSS_FIELD_ENUM
#define TYPE_F64 SSS_FIELD_DOUBLE
#define ROW(...) ROW_(__VA_ARGS__)
#define ROW_(key, member, type, place, when, def, lo, hi, lo_open, names, \
             count, help) \
	{#member, TYPE_##type, SSS__CAM_##when, offsetof(sss_camera, member), \
	 lo, hi, lo_open, names, count},
static const field fields[] = {SSS_CAMERA_FIELDS(ROW)};
#undef ROW
#undef ROW_
#undef TYPE_ENUM
#undef TYPE_F64

/* One member against its row. */
static sss_result check_field(const sss_camera *cam, const field *f,
                              char *errbuf, size_t errbuf_len)
{
	const char *at = (const char *)cam + f->offset;
	if (f->type == SSS_FIELD_ENUM) {
		int32_t v;
		memcpy(&v, at, sizeof v);
		for (int j = 0; j < f->name_count; j++)
			if (f->names[j].value == v)
				return SSS_OK;
		char list[64] = "";
		for (int j = 0; j < f->name_count; j++) {
			size_t used = strlen(list);
			snprintf(list + used, sizeof list - used, "%s%d", j ? ", " : "",
			         f->names[j].value);
		}
		return FAIL("camera: unknown %s %d (expected %s)", f->member, v,
		            list);
	}
	double v;
	memcpy(&v, at, sizeof v);
	char range[48];
	if (!sss__in_range(v, f->lo, f->hi, f->lo_open))
		return FAIL("camera: %s = %g is out of range (must be %s)",
		            f->member, v, sss__range_text(f->lo, f->hi, f->lo_open,
		                                          0, range, sizeof range));
	return SSS_OK;
}

sss_result sss__projection_make(const sss_camera *cam, int32_t width,
                                int32_t height, sss__projection *p,
                                char *errbuf, size_t errbuf_len)
{
	if (cam->struct_size != sizeof *cam)
		return FAIL("camera: struct_size %u, expected %zu (use "
		            "sss_camera_default)", cam->struct_size, sizeof *cam);
	/* The enums first: which lengths are read depends on the type. */
	for (int pass = 0; pass < 2; pass++)
		for (int k = 0; k < SSS__COUNT(fields); k++) {
			const field *f = &fields[k];
			if ((f->type == SSS_FIELD_ENUM) != !pass ||
			    (f->when == SSS__CAM_PERSP &&
			     cam->type != SSS_CAMERA_PERSPECTIVE) ||
			    (f->when == SSS__CAM_ORTHO &&
			     cam->type != SSS_CAMERA_ORTHOGRAPHIC))
				continue;
			sss_result r = check_field(cam, f, errbuf, errbuf_len);
			if (r)
				return r;
		}

	double ycor = cam->pixel_aspect_y / cam->pixel_aspect_x;
	int fit = cam->sensor_fit;
	double sensor = fit == SSS_SENSOR_FIT_VERTICAL ? cam->sensor_height_mm
	                                               : cam->sensor_width_mm;
	if (fit == SSS_SENSOR_FIT_AUTO)
		fit = cam->pixel_aspect_x * width >= cam->pixel_aspect_y * height
		      ? SSS_SENSOR_FIT_HORIZONTAL : SSS_SENSOR_FIT_VERTICAL;
	double viewfac = fit == SSS_SENSOR_FIT_HORIZONTAL ? (double)width
	                                                  : ycor * height;
	/* Size of one pixel (horizontally) at depth 1, or absolute (ortho). */
	double pixsize = cam->type == SSS_CAMERA_ORTHOGRAPHIC
	                 ? cam->ortho_scale : sensor / cam->lens_mm;
	pixsize /= viewfac;

	p->ortho = cam->type == SSS_CAMERA_ORTHOGRAPHIC;
	p->fx = 1.0 / pixsize;
	p->fy = 1.0 / (pixsize * ycor);
	p->cx = 0.5 * width - cam->shift_x * viewfac;
	p->cy = 0.5 * height + cam->shift_y * viewfac / ycor;
	return SSS_OK;
}

sss_result sss_camera_pixels_per_metre(const sss_camera *cam, int32_t width,
                                       int32_t height, double depth,
                                       double *pixels_per_metre, char *errbuf,
                                       size_t errbuf_len)
{
	if (errbuf && errbuf_len)
		errbuf[0] = '\0';
	if (!cam || !pixels_per_metre)
		return sss__fail(errbuf, errbuf_len, SSS_ERR_INVALID_ARGUMENT,
		                 "camera and pixels_per_metre are required");
	*pixels_per_metre = 0.0;
	if (width < 1 || height < 1)
		return sss__fail(errbuf, errbuf_len, SSS_ERR_INVALID_ARGUMENT,
		                 "image size %dx%d must be at least 1x1", width,
		                 height);
	sss__projection p;
	sss_result r = sss__projection_make(cam, width, height, &p, errbuf,
	                                    errbuf_len);
	if (r)
		return r;
	if (!p.ortho && !(isfinite(depth) && depth > 0.0))
		return sss__fail(errbuf, errbuf_len, SSS_ERR_INVALID_ARGUMENT,
		                 "depth %g must be finite and > 0", depth);
	*pixels_per_metre = sss__pixels_per_unit_x(&p, depth) / cam->unit_scale;
	return SSS_OK;
}

int sss__same_projection(const sss__projection *a, const sss__projection *b)
{
	return a->ortho == b->ortho && a->fx == b->fx && a->fy == b->fy &&
	       a->cx == b->cx && a->cy == b->cy;
}

double sss__pixels_per_unit_x(const sss__projection *p, double z)
{
	return p->ortho ? p->fx : p->fx / z;
}

double sss__pixels_per_unit_y(const sss__projection *p, double z)
{
	return p->ortho ? p->fy : p->fy / z;
}

double sss__reach_limit(const sss__projection *p, int32_t max_support_px,
                        int32_t width, int32_t height, double zmin,
                        double zmax)
{
	double px = fmin((double)max_support_px, hypot(width, height));
	double f = fmin(p->fx, p->fy);
	if (!(zmin <= zmax) || !(f > 0.0) || (!p->ortho && !(zmax > 0.0)))
		return 0.0;
	double across = px / f * (p->ortho ? 1.0 : zmax);
	double limit = SSS__REACH_FACTOR * hypot(across, zmax - zmin);
	return isfinite(limit) && limit > 0.0 ? limit : 0.0;
}

void sss__pixel_position(const sss__job *job, int32_t x, int32_t y,
                         double out[3])
{
	if (job->position) {
		const float *q = job->position + y * job->position_stride +
		                 (int64_t)x * job->position_channels;
		out[0] = q[0];
		out[1] = q[1];
		out[2] = q[2];
		return;
	}
	sss__view_point(&job->proj, x, y,
	                job->depth[y * job->depth_stride +
	                           (int64_t)x * job->depth_channels],
	                out);
}

void sss__view_point(const sss__projection *p, int32_t x, int32_t y,
                     double z, double out[3])
{
	double scale = p->ortho ? 1.0 : z;
	out[0] = (x + 0.5 - p->cx) / p->fx * scale;
	out[1] = (p->cy - (y + 0.5)) / p->fy * scale;
	out[2] = z;
}

/* The view cosine is computed in pixel-scaled view space, X' = fx X,
 * Y' = fy Y, Z' = Z, where a pixel's point needs no division: a tangent
 * t' maps back as t = S t' with S = diag(1/fx, 1/fy, 1), so the normal is
 * N = diag(fx, fy, 1) N' (up to det S) and N.V = N'.V' (perspective,
 * V = the point) up to the same factor. */
static void scaled_point(const sss__projection *p, int32_t x, int32_t y,
                         double z, double out[3])
{
	double scale = p->ortho ? 1.0 : z;
	out[0] = (x + 0.5 - p->cx) * scale;
	out[1] = (p->cy - (y + 0.5)) * scale;
	out[2] = z;
}

/* The step from pixel (x, y) to its neighbour along one axis, on the side
 * whose depth is nearer its own (so that a silhouette is not read as a
 * slope), from neighbours of the same slot only; 0 when neither is. */
static inline int surface_step(const sss_image *depth,
                               const int16_t *slot,
                               const sss__projection *p, int32_t w,
                               int32_t h, int32_t x, int32_t y, int dx,
                               int dy, const double here[3], double step[3])
{
	double best = INFINITY;
	int found = 0;
	int16_t own = slot[(size_t)y * w + x];
	for (int side = -1; side <= 1; side += 2) {
		int32_t nx = x + side * dx, ny = y + side * dy;
		if (nx < 0 || ny < 0 || nx >= w || ny >= h ||
		    slot[(size_t)ny * w + nx] != own)
			continue;
		double nz = sss__at(depth, nx, ny)[0];
		if (!(fabs(nz - here[2]) < best))
			continue;
		best = fabs(nz - here[2]);
		double there[3];
		scaled_point(p, nx, ny, nz, there);
		for (int c = 0; c < 3; c++)
			step[c] = side * (there[c] - here[c]);
		found = 1;
	}
	return found;
}

float sss__view_cosine(const sss_image *depth, const int16_t *slot,
                       const sss__projection *p, int32_t w, int32_t h,
                       int32_t x, int32_t y)
{
	double here[3], sx[3], sy[3];
	scaled_point(p, x, y, sss__at(depth, x, y)[0], here);
	if (!surface_step(depth, slot, p, w, h, x, y, 1, 0, here, sx) ||
	    !surface_step(depth, slot, p, w, h, x, y, 0, 1, here, sy))
		return 1.0f;
	/* N' = sx x sy; N = (fx N'x, fy N'y, N'z) */
	double nx = sx[1] * sy[2] - sx[2] * sy[1];
	double ny = sx[2] * sy[0] - sx[0] * sy[2];
	double nz = sx[0] * sy[1] - sx[1] * sy[0];
	double fx = p->fx, fy = p->fy;
	double nn = fx * fx * nx * nx + fy * fy * ny * ny + nz * nz;
	double dot, vv; /* N.V and |V|^2, both times fx fy (resp. its square) */
	if (p->ortho) { /* V = (0, 0, 1) */
		dot = nz * fx * fy;
		vv = fx * fx * fy * fy;
	} else {        /* V = (X'/fx, Y'/fy, Z) */
		dot = nx * here[0] + ny * here[1] + nz * here[2];
		dot *= fx * fy;
		vv = here[0] * here[0] * fy * fy + here[1] * here[1] * fx * fx +
		     here[2] * here[2] * fx * fx * fy * fy;
	}
	double den = nn * vv;
	if (!(den > 0.0) || !isfinite(den) || !isfinite(dot))
		return 1.0f;
	double mu = fabs(dot) / sqrt(den);
	return mu < 1.0 ? (float)mu : 1.0f;
}
