/* suggest.c - "did you mean" for mistyped commands and options: the nearest
 * known word by edit distance. */
#include "cli.h"

#include <string.h>

#define MAX_WORD 64

/* Optimal string alignment distance (insert, delete, substitute, swap two
 * neighbours), '-' and '_' counted alike: --max_iter is --max-iter. */
static int distance(const char *a, const char *b)
{
    int d[MAX_WORD + 1][MAX_WORD + 1];
    size_t n = strlen(a), m = strlen(b);

    if (n > MAX_WORD || m > MAX_WORD)
        return MAX_WORD;
    for (size_t i = 0; i <= n; i++)
        d[i][0] = (int)i;
    for (size_t j = 0; j <= m; j++)
        d[0][j] = (int)j;
    for (size_t i = 1; i <= n; i++)
        for (size_t j = 1; j <= m; j++) {
            char x = a[i - 1] == '_' ? '-' : a[i - 1],
                 y = b[j - 1] == '_' ? '-' : b[j - 1];
            int best = d[i - 1][j - 1] + (x != y);
            if (d[i - 1][j] + 1 < best)
                best = d[i - 1][j] + 1;
            if (d[i][j - 1] + 1 < best)
                best = d[i][j - 1] + 1;
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] &&
                d[i - 2][j - 2] + 1 < best)
                best = d[i - 2][j - 2] + 1;
            d[i][j] = best;
        }
    return d[n][m];
}

const char *cli_suggest(const char *word, const char *const *cands, size_t n)
{
    size_t len = strlen(word);
    /* a third of the word, 1 to 3 edits: "bondary" finds boundary, "ok" finds
     * nothing */
    int limit = len < 6 ? 1 : len < 9 ? 2 : 3, best = limit + 1;
    const char *near = NULL;

    for (size_t i = 0; i < n; i++) {
        int k = distance(word, cands[i]);
        /* a prefix of a long name (--bound for --boundary) is near too */
        if (k > limit && len >= 3 && !strncmp(word, cands[i], len))
            k = limit;
        if (k < best) {
            best = k;
            near = cands[i];
        }
    }
    return near;
}
