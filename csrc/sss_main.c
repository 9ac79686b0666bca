/* sss_main.c - the `sss` command: SSS post-process on Blender multilayer
 * EXR frames, without Blender. What a render farm runs after its render
 * tasks; the add-on takes the same path. */
#define _GNU_SOURCE /* getopt_long */
#include "sss.h"

#include <ctype.h>
#include <limits.h>
#include <errno.h>
#include <getopt.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* A printf format: the ranges, defaults and help of --samples,
 * --radius-scale and --threads are the library's options schema's
 * (print_usage). */
static const char usage_text[] =
"usage: sss INPUT.exr -o OUTPUT.exr --scene SCENE.json [options]\n"
"\n"
"Adds screen-space subsurface scattering to Blender multilayer EXR renders.\n"
"The output keeps every input channel and adds a layer SSS with the passes\n"
"Combined (RGBA) and DiffLight (the scattered diffuse light, RGB).\n"
"\n"
"The input needs, in one view layer: DiffDir and DiffCol (Diffuse Direct and\n"
"Color; DiffInd too for Cycles), Depth (Data: Z) and IndexMA (Data: Material\n"
"Index); GlossDir/Ind/Col, TransDir/Ind/Col, Emit, Env, Combined and\n"
"Position are used when present.\n"
"\n"
"options:\n"
"  -o, --output PATH       output file (#### pattern for sequences: every run\n"
"                          of # is the frame number, \\# a literal #); written\n"
"                          to a temporary file first, then renamed; only\n"
"                          ever replaces a writable regular file that is\n"
"                          neither the input nor the scene (not a device,\n"
"                          FIFO, directory or symbolic link)\n"
"  -s, --scene PATH        scene description (JSON: camera, unit scale,\n"
"                          materials by pass index; see docs/scene.md); a\n"
"                          file or a pipe\n"
"  -f, --frames LIST       frames for #### patterns: 1-240, 1-240x2, 7,9,12-20\n"
"  -m, --method NAME       scattering method, one of those below (default:\n"
"                          the scene's, else auto)\n"
"      --samples N         %s, %s\n"
"                          (default: the scene's, else %s)\n"
"  -r, --radius-scale F    multiply every radius by F %s (0 = no scattering:\n"
"                          SSS.Combined is then the recombined passes; a\n"
"                          back light baked at the scene's radius takes only\n"
"                          1 or 0)\n"
"  -l, --layer NAME        view layer to use (default: the first with DiffDir)\n"
"  -c, --compression NAME  output compression: zip (default), zips, piz,\n"
"                          rle, pxr24, b44, b44a, none (lossless: zip, zips,\n"
"                          piz, rle, none)\n"
"  -t, --threads N         %s, %s\n"
"                          (default: the scene's, else %s)\n"
"      --max-size WxH      refuse inputs larger than this, each 1..1048576\n"
"                          (default 32768x32768 and 2^28 pixels in all)\n"
"      --max-channels N    refuse inputs with more channels (default 4096)\n"
"      --max-memory SIZE   refuse inputs that take more memory decoded, in\n"
"                          bytes or with K, M, G, T (default: the machine's\n"
"                          physical memory)\n"
"      --resume            skip frames whose output exists and reads back\n"
"                          complete (outputs appear only when complete, so\n"
"                          a stopped run resumes)\n"
"  -q, --quiet             print errors only\n"
"  -h, --help              this text\n"
"  -V, --version           version\n";

static const char usage_examples[] =
"examples:\n"
"  sss shot.exr -o shot_sss.exr --scene shot.json\n"
"  sss render/frame_####.exr --frames 1-240 -o sss/frame_####.exr \\\n"
"      --scene shot.json --threads 8\n"
"  sss shot.exr -o check.exr --scene shot.json --radius-scale 0\n"
"\n"
"exit status: 0 all frames written, 1 some frame failed, 2 bad usage or scene.\n";

typedef struct args {
	const char *input, *output, *scene, *layer;
	const char *frames;
	int method;          /* -1 = the scene's */
	double radius_scale; /* multiplies the scene's */
	int compression;
	int threads;         /* -1 = the scene's */
	int samples;         /* -1 = the scene's */
	int max_w, max_h;
	long long max_pixels; /* 0: the library's default */
	long long max_channels, max_bytes; /* -1: the library's default */
	int quiet;
	int resume;
} args;

/* The row of the library's options schema (sss_option_field) for a
 * scene description key; the command's options that set the same
 * member take its range, default and help from it. */
static sss_field_info option_field(const char *key)
{
	sss_field_info f;
	for (int32_t i = 0; sss_option_field(i, &f) == SSS_OK; i++)
		if (strcmp(f.key, key) == 0)
			return f;
	/* Not reached with the library this was built with. */
	memset(&f, 0, sizeof f);
	f.key = key;
	f.help = key;
	f.hi = -1;
	return f;
}

/* The field's range as the command says it: "0..256", ">= 0". */
static const char *range_text(const sss_field_info *f, char *buf,
                              size_t len)
{
	if (f->hi >= (f->type == SSS_FIELD_INT ? INT32_MAX : 1e30))
		snprintf(buf, len, "%s %g", f->lo_open ? ">" : ">=", f->lo);
	else
		snprintf(buf, len, "%g..%g", f->lo, f->hi);
	return buf;
}

/* The options, then the library's methods with what each trades (words
 * wrapped to 78 columns), then the examples. */
static void print_usage(void)
{
	sss_field_info samples = option_field("samples");
	sss_field_info scale = option_field("radius_scale");
	sss_field_info threads = option_field("threads");
	char samples_range[48], scale_range[48], threads_range[48];
	char samples_default[24], threads_default[24];
	snprintf(samples_default, sizeof samples_default, "%g",
	         samples.default_value[0]);
	snprintf(threads_default, sizeof threads_default, "%g",
	         threads.default_value[0]);
	printf(usage_text, samples.help,
	       range_text(&samples, samples_range, sizeof samples_range),
	       samples_default,
	       range_text(&scale, scale_range, sizeof scale_range),
	       threads.help,
	       range_text(&threads, threads_range, sizeof threads_range),
	       threads_default);
	fputs("\nmethods:\n", stdout);
	for (int32_t m = 0; sss_method_name(m); m++) {
		int col = printf("  %-17s", sss_method_name(m));
		const char *w = sss_method_summary(m);
		for (int first = 1; *w; first = 0) {
			w += *w == ' ';
			int len = (int)strcspn(w, " ");
			if (!first && col + 1 + len > 78)
				col = printf("\n%19s", "") - 1;
			else if (!first)
				col += printf(" ");
			col += printf("%.*s", len, w);
			w += len;
		}
		printf("\n");
	}
	fputs("\n", stdout);
	fputs(usage_examples, stdout);
}

/* s with every control byte (ESC, CR, LF, ...) shown as \xNN, so that a
 * name from a file (a material, a layer, a path) can neither move the
 * terminal's cursor nor start a line of its own. */
static void put_clean(FILE *f, const char *s)
{
	for (; *s; s++) {
		unsigned char ch = (unsigned char)*s;
		if (ch < 0x20 || ch == 0x7f)
			fprintf(f, "\\x%02x", ch);
		else
			fputc(ch, f);
	}
}

/* "sss: <prefix><text>\n" on f, text cleaned. */
static void say(FILE *f, const char *prefix, const char *text)
{
	fprintf(f, "sss: %s", prefix);
	put_clean(f, text);
	fputc('\n', f);
}

/* "  methods: Skin disk, Jade separable" when any material's method
 * differs from the last frame's. */
static void tell_methods(const sss_scene *scene, int32_t n,
                         const int32_t *chosen, int32_t *told)
{
	if (memcmp(chosen, told, (size_t)n * sizeof *chosen) == 0)
		return;
	const char *sep = "  methods: ";
	for (int32_t m = 0; m < n; m++) {
		if (chosen[m] < 0)
			continue;
		const char *name = sss_scene_material_name(scene, m);
		fputs(sep, stdout);
		put_clean(stdout, name && *name ? name : "(unnamed)");
		printf(" %s", sss_method_name(chosen[m]));
		sep = ", ";
	}
	if (sep[0] == ',')
		putchar('\n');
	memcpy(told, chosen, (size_t)n * sizeof *chosen);
}

/* The method named `name`, or -1. */
static int method_by_name(const char *name)
{
	for (int32_t m = 0; sss_method_name(m); m++)
		if (strcmp(name, sss_method_name(m)) == 0)
			return m;
	return -1;
}

static int usage_error(const char *fmt, const char *what)
{
	char text[1024];
	snprintf(text, sizeof text, fmt, what);
	say(stderr, "", text);
	fprintf(stderr, "Try 'sss --help'.\n");
	return 2;
}

/* "--threads 'x' must be 0..256": what, then the field's range. */
static int option_error(const char *what, const sss_field_info *f,
                        const char *value)
{
	char fmt[128], range[48];
	snprintf(fmt, sizeof fmt, "%s %s", what,
	         range_text(f, range, sizeof range));
	return usage_error(fmt, value);
}

static int lookup(const char *name, const char *const *names, int count)
{
	for (int i = 0; i < count; i++)
		if (names[i] && strcmp(name, names[i]) == 0)
			return i;
	return -1;
}

/* Indexed by sss_exr_compression; DWAA/DWAB are absent from OpenEXR 3.1's
 * C API, so they are not offered. */
static const char *const compression_names[] = {"none", "rle", "zips", "zip",
                                                "piz", "pxr24", "b44", "b44a"};

/* ------------------------------------------------------------ numbers */

/* The whole of text as a decimal integer in [lo, hi]: no leading blanks,
 * nothing after the digits, range checked before any narrowing (strtoll
 * saturates out-of-range text, which is then refused too). */
static int parse_int(const char *text, long long lo, long long hi,
                     long long *out)
{
	char *end;
	if (!text || !*text || isspace((unsigned char)*text))
		return -1;
	errno = 0;
	long long v = strtoll(text, &end, 10);
	if (end == text || *end || errno || v < lo || v > hi)
		return -1;
	*out = v;
	return 0;
}

/* "WIDTHxHEIGHT", each 1..2^20, nothing else. */
static int parse_size(const char *text, int *w, int *h)
{
	char width[16];
	const char *x = strchr(text, 'x');
	long long a, b;
	if (!x || (size_t)(x - text) >= sizeof width)
		return -1;
	memcpy(width, text, (size_t)(x - text));
	width[x - text] = '\0';
	if (parse_int(width, 1, 1 << 20, &a) || parse_int(x + 1, 1, 1 << 20, &b))
		return -1;
	*w = (int)a;
	*h = (int)b;
	return 0;
}

/* "8G", "512M", "1048576", "0": bytes (K, M, G, T: powers of 1024). */
static int parse_bytes(const char *text, long long *out)
{
	static const char units[] = "KMGT";
	char digits[24];
	size_t n = strlen(text);
	const char *unit = n ? strchr(units, text[n - 1]) : NULL;
	int shift = unit && text[n - 1] ? 10 * (int)(unit - units + 1) : 0;
	if (shift)
		n--;
	if (n == 0 || n >= sizeof digits)
		return -1;
	memcpy(digits, text, n);
	digits[n] = '\0';
	long long v;
	if (parse_int(digits, 0, LLONG_MAX >> shift, &v))
		return -1;
	*out = v << shift;
	return 0;
}

/* Digits at *p (no sign) as a number up to limit, which *p moves past;
 * -1 when there are none, 1 when the number passes the limit. */
static int scan_uint(const char **p, long long limit, long long *out)
{
	const char *q = *p;
	long long v = 0;
	if (!isdigit((unsigned char)*q))
		return -1;
	for (; isdigit((unsigned char)*q); q++) {
		if (v > (limit - (*q - '0')) / 10)
			return 1;
		v = v * 10 + (*q - '0');
	}
	*p = q;
	*out = v;
	return 0;
}

/* ------------------------------------------------------------ frames */

#define MAX_FRAME 99999999LL
#define MAX_FRAMES 1000000LL

typedef struct frame_list {
	int *frames;
	int count;
} frame_list;

/* "1-240", "1-240x2", "7,9,12-20" -> frames in order; NULL, or what is
 * wrong (then out holds nothing). */
static const char *parse_frames(const char *text, frame_list *out)
{
	static const char *const form = "like 1-240, 1-240x2, 7,9,12-20";
	const char *why = NULL;
	long long cap = 0;
	out->frames = NULL;
	out->count = 0;
	const char *p = text;
	while (*p && !why) {
		long long a, b, step = 1;
		int r = scan_uint(&p, MAX_FRAME, &a);
		b = a;
		if (!r && *p == '-') {
			p++;
			r = scan_uint(&p, MAX_FRAME, &b);
			if (!r && *p == 'x') {
				p++;
				r = scan_uint(&p, MAX_FRAME, &step);
				if (!r && step < 1)
					why = "the step must be at least 1";
			}
		}
		if (r > 0)
			why = "frame numbers and steps must be 0..99999999";
		else if (r < 0)
			why = form;
		else if (!why && b < a)
			why = "a range must not run backwards";
		else if (!why && *p && *p != ',')
			why = form;
		if (why)
			break;
		long long n = (b - a) / step + 1; /* all <= MAX_FRAME: no overflow */
		if (n > MAX_FRAMES - out->count) {
			why = "at most 1000000 frames";
			break;
		}
		if (out->count + n > cap) {
			long long want = cap ? cap : 64;
			while (want < out->count + n)
				want *= 2;
			int *grown = realloc(out->frames, (size_t)want * sizeof *grown);
			if (!grown) {
				why = "out of memory";
				break;
			}
			out->frames = grown;
			cap = want;
		}
		for (long long i = 0; i < n; i++)
			out->frames[out->count++] = (int)(a + i * step);
		if (*p == ',' && !*++p)
			why = form; /* a trailing comma */
	}
	if (!why && out->count == 0)
		why = form;
	if (why) {
		free(out->frames);
		out->frames = NULL;
		out->count = 0;
	}
	return why;
}

/* Whether pattern has a '#' that is not written "\#". */
static int is_pattern(const char *pattern)
{
	for (const char *p = pattern; *p; p++) {
		if (p[0] == '\\' && p[1] == '#')
			p++;
		else if (*p == '#')
			return 1;
	}
	return 0;
}

/* Replaces every run of '#' in pattern with the frame number, zero-padded
 * to the run's length ("o_##_###.exr", frame 7: "o_07_007.exr"); "\#"
 * writes a literal '#'. 0, or -1 when out is too short. */
static int expand(const char *pattern, int frame, char *out, size_t len)
{
	size_t at = 0;
	for (const char *p = pattern; *p;) {
		char num[32];
		const char *piece = p;
		size_t n = 1;
		if (p[0] == '\\' && p[1] == '#') {
			piece = "#";
			p += 2;
		} else if (*p == '#') {
			int width = 0;
			while (p[width] == '#')
				width++;
			snprintf(num, sizeof num, "%0*d", width > 20 ? 20 : width,
			         frame);
			piece = num;
			n = strlen(num);
			p += width;
		} else {
			p++;
		}
		if (at + n >= len)
			return -1;
		memcpy(out + at, piece, n);
		at += n;
	}
	if (at >= len)
		return -1;
	out[at] = '\0';
	return 0;
}

/* The existing input files of a sequence, sorted by identity, so that an
 * output that is some other frame's input is found before any frame is
 * written (frame 1 of "in_1###.exr" as output is frame 1001's input). */
typedef struct frame_id {
	dev_t dev;
	ino_t ino;
	int frame;
} frame_id;

static int frame_id_cmp(const void *a, const void *b)
{
	const frame_id *x = a, *y = b;
	if (x->dev != y->dev)
		return x->dev < y->dev ? -1 : 1;
	if (x->ino != y->ino)
		return x->ino < y->ino ? -1 : 1;
	return 0;
}

/* 0, or -1 with what is wrong in err (nothing may be written then). */
static int check_sequence(const char *in_pattern, const char *out_pattern,
                          const frame_list *frames, char *err, size_t len)
{
	frame_id *ids = malloc((size_t)frames->count * sizeof *ids);
	int n = 0, bad = 0;
	char path[4096];
	struct stat st;
	if (!ids) {
		snprintf(err, len, "out of memory checking %d frames",
		         frames->count);
		return -1;
	}
	for (int i = 0; i < frames->count; i++)
		if (!expand(in_pattern, frames->frames[i], path, sizeof path) &&
		    stat(path, &st) == 0)
			ids[n++] = (frame_id){st.st_dev, st.st_ino, frames->frames[i]};
	qsort(ids, (size_t)n, sizeof *ids, frame_id_cmp);
	for (int i = 0; i < frames->count && !bad; i++) {
		if (expand(out_pattern, frames->frames[i], path, sizeof path) ||
		    stat(path, &st) != 0)
			continue;
		frame_id key = {st.st_dev, st.st_ino, 0};
		const frame_id *hit = bsearch(&key, ids, (size_t)n, sizeof *ids,
		                              frame_id_cmp);
		if (hit) {
			char other[4096];
			expand(in_pattern, hit->frame, other, sizeof other);
			snprintf(err, len, "frame %d's output %s is frame %d's input "
			         "%s; nothing was written", frames->frames[i], path,
			         hit->frame, other);
			bad = 1;
		}
	}
	free(ids);
	return bad ? -1 : 0;
}

/* ------------------------------------------------- stopping mid-write */

/* The temporary file being written (the library says, through
 * temporary_fn), so that a stopping signal (stop_signals) removes it
 * before the process dies of the signal; SIGKILL leaves it to the next
 * run's clean-up (see sss_exr_write). */
static char pending_temp[8192];
static volatile sig_atomic_t have_temp;

static void on_temporary(const char *path, void *user)
{
	(void)user;
	have_temp = 0;
	atomic_signal_fence(memory_order_seq_cst);
	if (path && strlen(path) < sizeof pending_temp) {
		memcpy(pending_temp, path, strlen(path) + 1);
		atomic_signal_fence(memory_order_seq_cst);
		have_temp = 1;
	}
}

/* The signals that stop a process by default and that a user, a shell
 * or a farm's scheduler sends: Ctrl-C, kill, a closed terminal or pipe,
 * an alarm, user signals, and the CPU-time and file-size limits
 * (ulimit -t, ulimit -f) that schedulers set. The faults (SIGSEGV, ...)
 * are not caught. Real-time signals also stop by default: caught too.
 * (Windows has only some of these.) */
static const struct {
	int sig;
	const char *name, *why;
} stop_signals[] = {
	{SIGINT, "SIGINT", "interrupted"},
	{SIGTERM, "SIGTERM", "terminated"},
	{SIGHUP, "SIGHUP", "its terminal closed"},
	{SIGQUIT, "SIGQUIT", "quit"},
#ifdef SIGPIPE
	{SIGPIPE, "SIGPIPE", "a closed pipe"},
#endif
#ifdef SIGALRM
	{SIGALRM, "SIGALRM", "an alarm"},
#endif
#ifdef SIGUSR1
	{SIGUSR1, "SIGUSR1", "a user signal"},
#endif
#ifdef SIGUSR2
	{SIGUSR2, "SIGUSR2", "a user signal"},
#endif
#ifdef SIGXCPU
	{SIGXCPU, "SIGXCPU", "its CPU time limit (ulimit -t)"},
#endif
#ifdef SIGXFSZ
	{SIGXFSZ, "SIGXFSZ", "its file size limit (ulimit -f)"},
#endif
#ifdef SIGVTALRM
	{SIGVTALRM, "SIGVTALRM", "a virtual timer"},
#endif
#ifdef SIGPROF
	{SIGPROF, "SIGPROF", "a profiling timer"},
#endif
#ifdef SIGPOLL
	{SIGPOLL, "SIGPOLL", "a pollable event"},
#endif
#ifdef SIGPWR
	{SIGPWR, "SIGPWR", "a power failure"},
#endif
};

/* Appends text at *at within buf (async-signal-safe). */
static void put(char *buf, size_t cap, size_t *at, const char *text)
{
	for (; *text && *at + 1 < cap; text++)
		buf[(*at)++] = *text;
}

/* "sss: stopped by SIGXFSZ (its file size limit (ulimit -f)); removed the
 * temporary X", written with write(2) only. */
static void on_signal(int sig)
{
	static char msg[sizeof pending_temp + 256];
	size_t at = 0;
	const char *name = "a signal", *why = "";
	for (size_t i = 0; i < sizeof stop_signals / sizeof *stop_signals; i++)
		if (stop_signals[i].sig == sig) {
			name = stop_signals[i].name;
			why = stop_signals[i].why;
		}
	put(msg, sizeof msg, &at, "\nsss: stopped by ");
	put(msg, sizeof msg, &at, name);
	if (why[0]) {
		put(msg, sizeof msg, &at, " (");
		put(msg, sizeof msg, &at, why);
		put(msg, sizeof msg, &at, ")");
	}
	if (have_temp && unlink(pending_temp) == 0) {
		put(msg, sizeof msg, &at, "; removed the unfinished ");
		put(msg, sizeof msg, &at, pending_temp);
	}
	put(msg, sizeof msg, &at, "\n");
#ifdef SIGPIPE
	if (sig == SIGPIPE) /* stderr may be that pipe */
		at = 0;
#endif
	if (at)
		(void)!write(STDERR_FILENO, msg, at);
	signal(sig, SIG_DFL);
	raise(sig);
}

static void catch_one(int sig, const struct sigaction *sa)
{
	struct sigaction old;
	/* An ignored signal stays ignored (nohup, a shell's &). */
	if (sigaction(sig, NULL, &old) == 0 && old.sa_handler != SIG_IGN)
		sigaction(sig, sa, NULL);
}

static void catch_signals(void)
{
	struct sigaction sa;
	memset(&sa, 0, sizeof sa);
	sa.sa_handler = on_signal;
	sigfillset(&sa.sa_mask); /* one handler at a time */
	for (size_t i = 0; i < sizeof stop_signals / sizeof *stop_signals; i++)
		catch_one(stop_signals[i].sig, &sa);
#if defined(SIGRTMIN) && defined(SIGRTMAX)
	for (int sig = SIGRTMIN; sig <= SIGRTMAX; sig++)
		catch_one(sig, &sa);
#endif
}

/* ----------------------------------------------------- per-frame checks */

typedef struct file_id {
	int known;
	dev_t dev;
	ino_t ino;
} file_id;

static file_id identify(const char *path)
{
	struct stat st;
	file_id id = {0, 0, 0};
	if (path && stat(path, &st) == 0)
		id = (file_id){1, st.st_dev, st.st_ino};
	return id;
}

static int same(file_id a, file_id b)
{
	return a.known && b.known && a.dev == b.dev && a.ino == b.ino;
}

/* What must hold before a frame's work starts: out may be written and is
 * neither its input nor the scene. 0, or the message in err. */
static int check_frame(const char *in, const char *out, file_id scene,
                       const char *scene_path, char *err, size_t len)
{
	if (sss_exr_check_output(out, err, len) != SSS_OK)
		return -1;
	file_id o = identify(out);
	if (same(o, identify(in))) {
		snprintf(err, len, "%s: is the input file %s; refusing to "
		         "overwrite it", out, in);
		return -1;
	}
	if (same(o, scene)) {
		snprintf(err, len, "%s: is the scene description %s; refusing "
		         "to overwrite it", out, scene_path);
		return -1;
	}
	return 0;
}

/* --resume: an existing output counts as done only if it reads back
 * whole with the SSS layer (an empty or cut file from a crash, or some
 * other file under that name, does not). */
static int complete_output(const char *out, const sss_exr_options *o,
                           char *why, size_t len)
{
	sss_exr *exr = NULL;
	sss_image view;
	if (sss_exr_read(out, o, &exr, why, len) != SSS_OK)
		return 0;
	int ok = sss_exr_find(exr, SSS_RESULT_LAYER, "Combined", &view) ==
	         SSS_OK;
	if (!ok)
		snprintf(why, len, "%s: has no %s.Combined pass", out,
		         SSS_RESULT_LAYER);
	sss_exr_free(exr);
	return ok;
}

static void progress_bar(int done, int total, int failed)
{
	int width = 30, fill = total ? done * width / total : width;
	fprintf(stderr, "\r[%.*s%*s] %d/%d frames%s", fill,
	        "##############################", width - fill, "", done, total,
	        failed ? " (some failed)" : "");
	if (done == total)
		fputc('\n', stderr);
	fflush(stderr);
}

/* The options' defaults: the scene's or the library's everywhere. */
static args args_default(void)
{
	return (args){.method = -1, .radius_scale = 1.0, .compression = -1,
	              .threads = -1, .samples = -1, .max_w = 32768,
	              .max_h = 32768, .max_pixels = 0, .max_channels = -1,
	              .max_bytes = -1};
}

/* The command line into *a: -1 to go on, else the exit status (0 after
 * --help or --version, 2 for bad usage, said on stderr). */
static int parse_args(int argc, char **argv, args *a)
{
	static const struct option longopts[] = {
		{"output", required_argument, NULL, 'o'},
		{"scene", required_argument, NULL, 's'},
		{"frames", required_argument, NULL, 'f'},
		{"method", required_argument, NULL, 'm'},
		{"radius-scale", required_argument, NULL, 'r'},
		{"layer", required_argument, NULL, 'l'},
		{"compression", required_argument, NULL, 'c'},
		{"threads", required_argument, NULL, 't'},
		{"max-size", required_argument, NULL, 'S'},
		{"samples", required_argument, NULL, 'N'},
		{"max-channels", required_argument, NULL, 'C'},
		{"max-memory", required_argument, NULL, 'M'},
		{"quiet", no_argument, NULL, 'q'},
		{"resume", no_argument, NULL, 'R'},
		{"help", no_argument, NULL, 'h'},
		{"version", no_argument, NULL, 'V'},
		{NULL, 0, NULL, 0},
	};
	int c;
	char *end;
	long long n;
	sss_field_info field;
	while ((c = getopt_long(argc, argv, "o:s:f:m:r:l:c:t:qhV", longopts,
	                        NULL)) != -1) {
		switch (c) {
		case 'o': a->output = optarg; break;
		case 's': a->scene = optarg; break;
		case 'f': a->frames = optarg; break;
		case 'l': a->layer = optarg; break;
		case 'q': a->quiet = 1; break;
		case 'R': a->resume = 1; break;
		case 'h': print_usage(); return 0;
		case 'V':
			printf("sss %s (libsss ABI %u)\n", sss_version_string(),
			       sss_abi_version());
			return 0;
		case 'm':
			a->method = method_by_name(optarg);
			if (a->method < 0)
				return usage_error("unknown method '%s' (sss --help "
				                   "lists them)", optarg);
			break;
		case 'c':
			a->compression = lookup(optarg, compression_names, 8);
			if (a->compression < 0)
				return usage_error("unknown compression '%s'", optarg);
			break;
		case 'r':
			field = option_field("radius_scale");
			errno = 0;
			a->radius_scale = strtod(optarg, &end);
			if (*end || end == optarg || errno ||
			    isspace((unsigned char)*optarg) ||
			    !(a->radius_scale >= field.lo) ||
			    (field.lo_open && !(a->radius_scale > field.lo)) ||
			    a->radius_scale > (field.hi < 1e30 ? field.hi : 1e30))
				return option_error("--radius-scale '%s' must be a "
				                    "number", &field, optarg);
			break;
		case 't':
			field = option_field("threads");
			if (parse_int(optarg, (long long)field.lo, (long long)field.hi,
			              &n))
				return option_error("--threads '%s' must be", &field,
				                    optarg);
			a->threads = (int)n;
			break;
		case 'N':
			field = option_field("samples");
			if (parse_int(optarg, (long long)field.lo, (long long)field.hi,
			              &n))
				return option_error("--samples '%s' must be", &field,
				                    optarg);
			a->samples = (int)n;
			break;
		case 'C':
			if (parse_int(optarg, 1, INT32_MAX, &a->max_channels))
				return usage_error("--max-channels '%s' must be "
				                   "1..2147483647", optarg);
			break;
		case 'M':
			if (parse_bytes(optarg, &a->max_bytes))
				return usage_error("--max-memory '%s' must be a size "
				                   "like 8G, 512M or 0 (the machine's "
				                   "memory)", optarg);
			break;
		case 'S':
			if (parse_size(optarg, &a->max_w, &a->max_h))
				return usage_error("--max-size '%s' must be WIDTHxHEIGHT, "
				                   "each 1..1048576", optarg);
			a->max_pixels = (long long)a->max_w * a->max_h;
			break;
		default:
			fprintf(stderr, "Try 'sss --help'.\n");
			return 2;
		}
	}
	if (optind != argc - 1)
		return usage_error("%s", optind >= argc
		                   ? "missing INPUT file"
		                   : "exactly one INPUT file (use #### and --frames "
		                     "for sequences)");
	a->input = argv[optind];
	if (!a->output)
		return usage_error("%s", "missing -o OUTPUT");
	if (!a->output[0])
		return usage_error("%s", "-o OUTPUT is empty");
	if (!a->scene)
		return usage_error("%s", "missing --scene SCENE.json (camera and "
		                         "materials)");
	int in_seq = is_pattern(a->input);
	if (in_seq != is_pattern(a->output))
		return usage_error("%s", "INPUT and OUTPUT must both be #### "
		                         "patterns, or neither");
	if (in_seq && !a->frames)
		return usage_error("%s", "a #### pattern needs --frames");
	if (!in_seq && a->frames)
		return usage_error("%s", "--frames needs #### patterns");
	return -1;
}

/* What the command line asks of sss_process_exr. */
static void process_options(const args *a, sss_process_options *po)
{
	sss_process_options_default(po);
	po->layer = a->layer;
	po->method = a->method;
	po->num_threads = a->threads;
	po->samples = a->samples;
	po->radius_scale = (float)a->radius_scale;
	po->exr.max_width = a->max_w;
	po->exr.max_height = a->max_h;
	if (a->max_pixels)
		po->exr.max_pixels = a->max_pixels;
	if (a->compression >= 0)
		po->exr.compression = a->compression;
	if (a->max_channels > 0)
		po->exr.max_channels = (int32_t)a->max_channels;
	if (a->max_bytes >= 0)
		po->exr.max_bytes = a->max_bytes;
	po->exr.temporary_fn = on_temporary;
}

/* One run over the frames: what every frame shares and the tallies. */
typedef struct batch {
	const args *a;
	int in_seq;
	int bar;                 /* a progress bar on the terminal */
	sss_scene *scene;
	file_id scene_id;
	sss_process_options po;
	int32_t nmat;
	int32_t *chosen, *told;  /* the method each material ran; as told */
	int failed, skipped;
	sss_timings total;
	char err[10240];
} batch;

/* Frame f (the i-th of count): checked, skipped (--resume) or processed,
 * and said. */
static void run_frame(batch *b, int i, int f, int count)
{
	const args *a = b->a;
	char in[4096], out[4096];
	sss_timings t = {0, 0, 0};
	int bad = 0;
	char why[sizeof b->err];
	if (expand(a->input, f, in, sizeof in) ||
	    expand(a->output, f, out, sizeof out)) {
		const char *which = expand(a->input, f, in, sizeof in) ? a->input
		                                                       : a->output;
		char frame[32] = "";
		if (b->in_seq)
			snprintf(frame, sizeof frame, "frame %d: ", f);
		snprintf(b->err, sizeof b->err, "%sthe path made from %.80s... is "
		         "longer than %zu bytes", frame, which, sizeof in - 1);
		bad = 1;
	} else if (check_frame(in, out, b->scene_id, a->scene, b->err,
	                       sizeof b->err)) {
		bad = 1;
	} else if (a->resume && access(out, F_OK) == 0 &&
	           complete_output(out, &b->po.exr, why, sizeof why)) {
		b->skipped++;
		if (!a->quiet) {
			put_clean(stdout, out);
			printf(": exists, skipped (--resume)\n");
		}
		if (b->bar)
			progress_bar(i + 1, count, b->failed);
		return;
	} else {
		if (a->resume && access(out, F_OK) == 0) {
			char line[sizeof why + 4096 + 128];
			snprintf(line, sizeof line, "%s: exists but is not a "
			         "complete output (%s); writing it again", out, why);
			say(stderr, "", line);
		}
		bad = sss_process_exr(in, out, b->scene, &b->po, &t, b->err,
		                      sizeof b->err) != SSS_OK;
	}
	if (b->bar)
		fputc('\r', stderr);
	if (bad) {
		b->failed++;
		say(stderr, "error: ", b->err);
	} else if (!a->quiet) {
		put_clean(stdout, in);
		fputs(" -> ", stdout);
		put_clean(stdout, out);
		printf(": read %.3f s, sss %.3f s, write %.3f s\n", t.read,
		       t.scatter, t.write);
		if (b->chosen)
			tell_methods(b->scene, b->nmat, b->chosen, b->told);
		fflush(stdout);
	}
	b->total.read += t.read;
	b->total.scatter += t.scatter;
	b->total.write += t.write;
	if (b->bar)
		progress_bar(i + 1, count, b->failed);
}

int main(int argc, char **argv)
{
	args a = args_default();
	int status = parse_args(argc, argv, &a);
	if (status >= 0)
		return status;

	frame_list frames = {NULL, 0};
	int single = 0;
	if (a.frames) {
		const char *why = parse_frames(a.frames, &frames);
		if (why) {
			fprintf(stderr, "sss: bad --frames '");
			put_clean(stderr, a.frames);
			fprintf(stderr, "': %s\nTry 'sss --help'.\n", why);
			return 2;
		}
	} else {
		frames.frames = &single;
		frames.count = 1;
	}

	batch b = {.a = &a, .in_seq = is_pattern(a.input)};
	char warn[4096] = "";
	sss_result r = sss_scene_load(a.scene, &b.scene, warn, sizeof warn,
	                              b.err, sizeof b.err);
	/* warnings: one line each */
	for (char *line = warn; *line;) {
		char *nl = strchr(line, '\n');
		if (nl)
			*nl = '\0';
		if (*line)
			say(stderr, "", line);
		line = nl ? nl + 1 : line + strlen(line);
	}
	if (r) {
		say(stderr, "", b.err);
		if (frames.frames != &single)
			free(frames.frames);
		return 2;
	}

	if (b.in_seq && check_sequence(a.input, a.output, &frames, b.err,
	                               sizeof b.err)) {
		say(stderr, "error: ", b.err);
		sss_scene_free(b.scene);
		free(frames.frames);
		return 2;
	}
	b.scene_id = identify(a.scene);
	catch_signals();
	b.bar = !a.quiet && isatty(STDERR_FILENO) && frames.count > 1;
	process_options(&a, &b.po);
	/* The method each material ran, told when it changes (auto chooses
	 * per frame). */
	sss_scene_materials(b.scene, &b.nmat);
	size_t slots = (size_t)(b.nmat > 0 ? b.nmat : 1);
	b.chosen = calloc(2 * slots, sizeof *b.chosen);
	b.told = b.chosen ? b.chosen + slots : NULL;
	if (b.told)
		for (int32_t m = 0; m < b.nmat; m++)
			b.told[m] = -2;
	b.po.chosen_methods = b.chosen;
	for (int i = 0; i < frames.count; i++)
		run_frame(&b, i, frames.frames[i], frames.count);
	if (!a.quiet && frames.count > 1)
		printf("%d frames: %d written, %d skipped, %d failed; read %.2f s, "
		       "sss %.2f s, write %.2f s\n", frames.count,
		       frames.count - b.failed - b.skipped, b.skipped, b.failed,
		       b.total.read, b.total.scatter, b.total.write);
	sss_scene_free(b.scene);
	free(b.chosen);
	if (frames.frames != &single)
		free(frames.frames);
	/* A report that could not be written (a full disk, a closed pipe) is
	 * a failure too, not exit status 0. */
	if (fflush(stdout) != 0 || ferror(stdout)) {
		fprintf(stderr, "sss: error: cannot write to standard output: %s\n",
		        strerror(errno));
		return 1;
	}
	return b.failed ? 1 : 0;
}
