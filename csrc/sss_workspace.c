/* sss_workspace.c - the working memory of a scatter, kept for the next
 * one. A scatter at 1080p needs some 55 MB of planes; taken fresh every
 * time, the system hands them over as new pages, and faulting those in
 * cost about a tenth of a re-tune (1080p demo, two threads: 0.162 s
 * against 0.145 s with the memory kept). A kept frame (sss_frame.c) holds
 * one workspace between its scatters; without one every block is
 * allocated and freed as usual. Planes that depend only on the depth, the
 * camera and the slot map live here too, noted with the slot map they
 * were made from (sss__ws_note_slots) and remade when it changes. */
#include "sss_internal.h"

#include <stdlib.h>
#include <string.h>

struct sss__workspace {
	void *block[SSS__WS_BLOCKS];
	size_t size[SSS__WS_BLOCKS];
};

sss__workspace *sss__workspace_new(void)
{
	return calloc(1, sizeof(sss__workspace));
}

void sss__workspace_free(sss__workspace *ws)
{
	if (!ws)
		return;
	for (int b = 0; b < SSS__WS_BLOCKS; b++)
		free(ws->block[b]);
	free(ws);
}

void *sss__ws_get(sss__workspace *ws, int block, size_t bytes, int zeroed)
{
	if (!bytes)
		bytes = 1;
	if (!ws)
		return zeroed ? calloc(bytes, 1) : malloc(bytes);
	if (ws->size[block] < bytes) {
		free(ws->block[block]);
		ws->size[block] = 0;
		if (!(ws->block[block] = malloc(bytes)))
			return NULL;
		ws->size[block] = bytes;
	}
	if (zeroed)
		memset(ws->block[block], 0, bytes);
	return ws->block[block];
}

void sss__ws_put(sss__workspace *ws, void *p)
{
	if (!ws)
		free(p);
}

void *sss__ws_kept(sss__workspace *ws, int block, size_t bytes)
{
	return ws && ws->block[block] && ws->size[block] >= bytes
	       ? ws->block[block] : NULL;
}

int sss__ws_same_slots(sss__workspace *ws, int block, const int16_t *slot,
                       size_t npix)
{
	const int16_t *kept = sss__ws_kept(ws, block, npix * sizeof *kept);
	return kept && memcmp(kept, slot, npix * sizeof *kept) == 0;
}

sss_result sss__ws_note_slots(sss__workspace *ws, int block,
                              const int16_t *slot, size_t npix)
{
	int16_t *copy = sss__ws_get(ws, block, npix * sizeof *copy, 0);
	if (!copy)
		return SSS_ERR_OUT_OF_MEMORY;
	memcpy(copy, slot, npix * sizeof *copy);
	return SSS_OK;
}

void sss__ws_forget(sss__workspace *ws, int block)
{
	if (ws) {
		free(ws->block[block]);
		ws->block[block] = NULL;
		ws->size[block] = 0;
	}
}
