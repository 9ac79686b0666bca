/* sss_options.c - the options' schema (sss_option_fields.h) as data:
 * their check and sss_option_field(). */
#include "sss_internal.h"
#include "sss_option_fields.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

typedef struct field {
	const char *key, *member;
	int32_t type; /* sss_field_type */
	size_t offset;
	double def, lo, hi;
	int32_t lo_open;
	const char *help;
} field;

#define TYPE_METHOD SSS_FIELD_ENUM
#define TYPE_F32 SSS_FIELD_FLOAT
#define TYPE_F64 SSS_FIELD_DOUBLE
#define TYPE_INT SSS_FIELD_INT
#define ROW(key, member, type, def, lo, hi, lo_open, help) \
	{key, #member, TYPE_##type, offsetof(sss_options, member), def, lo, hi, \
	 lo_open, help},
static const field fields[] = {SSS_OPTION_FIELDS(ROW)};
#undef ROW
#undef TYPE_METHOD
#undef TYPE_F32
#undef TYPE_F64
#undef TYPE_INT

static int32_t method_count(void)
{
	int32_t n = 0;
	while (sss_method_name(n))
		n++;
	return n;
}

sss_result sss_option_field(int32_t i, sss_field_info *info)
{
	if (!info || i < 0 || i >= SSS__COUNT(fields))
		return SSS_ERR_INVALID_ARGUMENT;
	const field *f = &fields[i];
	memset(info, 0, sizeof *info);
	info->key = f->key;
	info->member = f->member;
	info->type = f->type;
	info->profile = -1;
	info->default_value[0] = f->def;
	info->lo = f->lo;
	info->hi = f->type == SSS_FIELD_ENUM ? method_count() - 1 : f->hi;
	info->lo_open = f->lo_open;
	info->name_count = f->type == SSS_FIELD_ENUM ? method_count() : 0;
	info->help = f->help;
	return SSS_OK;
}

/* One member against its row: the first that is out of range is named,
 * with its range, in the message. */
static sss_result check_field(const sss_options *o, const field *f,
                              char *errbuf, size_t errbuf_len)
{
	const char *at = (const char *)o + f->offset;
	char range[48];
	if (f->type == SSS_FIELD_ENUM || f->type == SSS_FIELD_INT) {
		int32_t v;
		memcpy(&v, at, sizeof v);
		if (f->type == SSS_FIELD_ENUM) {
			if (!sss_method_name(v))
				return FAIL("options: unknown %s %d (expected 0..%d)",
				            f->member, v, method_count() - 1);
		} else if (v < f->lo || v > f->hi) {
			return FAIL("options: %s %d must be %s", f->member, v,
			            sss__range_text(f->lo, f->hi, f->lo_open, 1, range,
			                            sizeof range));
		}
		return SSS_OK;
	}
	double v;
	if (f->type == SSS_FIELD_FLOAT) {
		float x;
		memcpy(&x, at, sizeof x);
		v = x;
	} else {
		memcpy(&v, at, sizeof v);
	}
	if (!sss__in_range(v, f->lo, f->hi, f->lo_open))
		return FAIL("options: %s %g must be %s", f->member, v,
		            sss__range_text(f->lo, f->hi, f->lo_open, 0, range,
		                            sizeof range));
	return SSS_OK;
}

int sss__option_in_range(const char *key, double v, char *range,
                          size_t range_len)
{
	for (int k = 0; k < SSS__COUNT(fields); k++) {
		const field *f = &fields[k];
		if (strcmp(f->key, key) != 0)
			continue;
		sss__range_text(f->lo, f->hi, f->lo_open, f->type == SSS_FIELD_INT,
		                range, range_len);
		return sss__in_range(v, f->lo, f->hi, f->lo_open);
	}
	snprintf(range, range_len, "?");
	return 0;
}

sss_result sss__options_check(const sss_options *o, char *errbuf,
                              size_t errbuf_len)
{
	if (o->struct_size != sizeof *o)
		return FAIL("options: struct_size %u, expected %zu (use "
		            "sss_options_default)", o->struct_size, sizeof *o);
	for (int k = 0; k < SSS__COUNT(fields); k++) {
		sss_result r = check_field(o, &fields[k], errbuf, errbuf_len);
		if (r)
			return r;
	}
	return SSS_OK;
}
