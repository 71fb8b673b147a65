/* poll.c - progress channels, parked connections and their deadlines.
 * Lock order: hub lock, then MHD's own locks (MHD_suspend_connection and
 * MHD_resume_connection are called with the hub lock held, which is what makes
 * "check, then park" atomic against "publish, then resume all"). A waiter is
 * unlinked before its connection is resumed, so once resumed nothing here
 * points at the request any more and MHD may free it. */
#define _GNU_SOURCE
#include "poll.h"

#include <poll.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* How long a finished run's records stay in memory (then readers use the file),
 * and how long an empty channel created by a parker may sit unused. */
#define CHAN_DONE_TTL 120.0
#define CHAN_IDLE_TTL 600.0
/* How often the parked sockets are checked for clients that hung up. */
#define SWEEP_INTERVAL 1.0
/* Recent kicks remembered for poll_park_since. */
#define KICK_RING 256

typedef struct poll_chan {
    struct poll_chan *next;
    char id[64];
    char **rec;
    size_t *rlen;
    long n, cap;
    int done;
    int local;      /* a run of this process (begin/publish): records are here */
    double touched; /* mono time of the last begin/publish/end/park */
    poll_waiter *waiters;
} poll_chan;

struct poll_hub {
    pthread_mutex_t lock;
    pthread_cond_t cond;
    pthread_t timer;
    int timer_running;
    int stop, shutting_down;
    int nparked;
    long ngone;
    double swept; /* mono time of the last sweep */
    struct pollfd *pfd;
    poll_waiter **pw;
    size_t pcap;
    poll_chan *chans;
    /* kicks: kick k (k = 1, 2, ...) named ring[k % KICK_RING]; kick_all_gen
     * is the gen of the last kick of everything */
    unsigned long kick_gen, kick_all_gen;
    char ring[KICK_RING][64];
};

poll_hub *poll_new(void)
{
    poll_hub *h = calloc(1, sizeof *h);
    pthread_condattr_t ca;

    if (!h)
        return NULL;
    pthread_mutex_init(&h->lock, NULL);
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&h->cond, &ca);
    pthread_condattr_destroy(&ca);
    return h;
}

static poll_chan *find(poll_hub *h, const char *id)
{
    for (poll_chan *c = h->chans; c; c = c->next)
        if (!strcmp(c->id, id))
            return c;
    return NULL;
}

static poll_chan *find_or_add(poll_hub *h, const char *id)
{
    poll_chan *c = find(h, id);
    if (c)
        return c;
    c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    snprintf(c->id, sizeof c->id, "%s", id);
    c->touched = mono_now();
    c->next = h->chans;
    h->chans = c;
    return c;
}

static void clear_records(poll_chan *c)
{
    for (long i = 0; i < c->n; i++)
        free(c->rec[i]);
    c->n = 0;
}

static void unlink_waiter(poll_hub *h, poll_waiter *w)
{
    poll_chan *c = w->chan;
    if (w->prev)
        w->prev->next = w->next;
    else
        c->waiters = w->next;
    if (w->next)
        w->next->prev = w->prev;
    w->next = w->prev = NULL;
    w->chan = NULL;
    w->parked = 0;
    h->nparked--;
}

/* Resume one waiter; hub lock held. */
static void wake(poll_hub *h, poll_waiter *w)
{
    struct MHD_Connection *conn = w->conn;
    unlink_waiter(h, w);
    MHD_resume_connection(conn);
}

static void wake_all(poll_hub *h, poll_chan *c)
{
    while (c->waiters)
        wake(h, c->waiters);
}

static void free_chan(poll_chan *c)
{
    clear_records(c);
    free(c->rec);
    free(c->rlen);
    free(c);
}

/* Resume the parked connections whose client closed its end (FIN or reset);
 * hub lock held. A parked connection stays suspended, so its socket stays
 * open while it is linked here. */
static void sweep_gone(poll_hub *h)
{
    size_t n = 0;

    if ((size_t)h->nparked > h->pcap) {
        size_t cap = (size_t)h->nparked + 64;
        struct pollfd *pf = realloc(h->pfd, cap * sizeof *pf);
        if (pf)
            h->pfd = pf;
        poll_waiter **pw = realloc(h->pw, cap * sizeof *pw);
        if (pw)
            h->pw = pw;
        if (!pf || !pw)
            return; /* try again next time */
        h->pcap = cap;
    }
    for (poll_chan *c = h->chans; c; c = c->next)
        for (poll_waiter *w = c->waiters; w; w = w->next)
            if (w->fd >= 0 && n < h->pcap) {
                h->pfd[n] = (struct pollfd){.fd = w->fd, .events = POLLRDHUP};
                h->pw[n++] = w;
            }
    if (!n || poll(h->pfd, n, 0) <= 0)
        return;
    for (size_t i = 0; i < n; i++)
        if (h->pfd[i].revents & (POLLRDHUP | POLLHUP | POLLERR | POLLNVAL)) {
            h->pw[i]->gone = 1;
            h->ngone++;
            wake(h, h->pw[i]);
        }
}

static void *timer_main(void *arg)
{
    poll_hub *h = arg;

    pthread_mutex_lock(&h->lock);
    while (!h->stop) {
        double now = mono_now();
        if (now - h->swept >= SWEEP_INTERVAL) {
            sweep_gone(h);
            h->swept = now;
        }
        double next = h->swept + SWEEP_INTERVAL;
        poll_chan **pp = &h->chans;
        while (*pp) {
            poll_chan *c = *pp;
            poll_waiter *w = c->waiters;
            while (w) {
                poll_waiter *nx = w->next;
                if (w->deadline <= now)
                    wake(h, w);
                else if (w->deadline < next)
                    next = w->deadline;
                w = nx;
            }
            if (!c->waiters && ((c->done && now - c->touched > CHAN_DONE_TTL) ||
                                (!c->n && now - c->touched > CHAN_IDLE_TTL))) {
                *pp = c->next;
                free_chan(c);
                continue;
            }
            pp = &c->next;
        }
        struct timespec ts;
        ts.tv_sec = (time_t)next;
        ts.tv_nsec = (long)((next - (double)ts.tv_sec) * 1e9);
        pthread_cond_timedwait(&h->cond, &h->lock, &ts);
    }
    pthread_mutex_unlock(&h->lock);
    return NULL;
}

int poll_start(poll_hub *h)
{
    if (pthread_create(&h->timer, NULL, timer_main, h))
        return -1;
    h->timer_running = 1;
    return 0;
}

void poll_shutdown(poll_hub *h)
{
    pthread_mutex_lock(&h->lock);
    h->shutting_down = 1;
    for (poll_chan *c = h->chans; c; c = c->next)
        wake_all(h, c);
    pthread_mutex_unlock(&h->lock);
}

void poll_free(poll_hub *h)
{
    if (!h)
        return;
    pthread_mutex_lock(&h->lock);
    h->stop = 1;
    pthread_cond_broadcast(&h->cond);
    pthread_mutex_unlock(&h->lock);
    if (h->timer_running)
        pthread_join(h->timer, NULL);
    while (h->chans) {
        poll_chan *c = h->chans;
        h->chans = c->next;
        free_chan(c);
    }
    pthread_cond_destroy(&h->cond);
    pthread_mutex_destroy(&h->lock);
    free(h->pfd);
    free(h->pw);
    free(h);
}

void poll_begin(poll_hub *h, const char *id)
{
    pthread_mutex_lock(&h->lock);
    poll_chan *c = find_or_add(h, id);
    if (c) {
        clear_records(c);
        c->done = 0;
        c->local = 1;
        c->touched = mono_now();
    }
    pthread_mutex_unlock(&h->lock);
}

long poll_publish(poll_hub *h, const char *id, const char *json, size_t len,
                  sbuf *line_out)
{
    sbuf line = {0};
    long seq = -1;
    poll_chan *c;

    pthread_mutex_lock(&h->lock);
    c = find_or_add(h, id);
    if (!c)
        goto out;
    c->local = 1;
    if (c->n == c->cap) {
        long cap = c->cap ? 2 * c->cap : 32;
        char **r = realloc(c->rec, (size_t)cap * sizeof *r);
        if (!r)
            goto out;
        c->rec = r;
        size_t *l = realloc(c->rlen, (size_t)cap * sizeof *l);
        if (!l)
            goto out;
        c->rlen = l;
        c->cap = cap;
    }
    /* The record is one JSON object; seq goes in first so readers can resume
     * from it, whatever iteration numbering the optimizer uses. */
    sb_printf(&line, "{\"seq\":%ld", c->n);
    if (len > 2 && json[0] == '{') {
        sb_puts(&line, ",");
        sb_add(&line, json + 1, len - 1);
    } else {
        sb_puts(&line, "}");
    }
    if (line.oom)
        goto out;
    seq = c->n;
    c->rec[c->n] = line.buf;
    c->rlen[c->n] = line.len;
    c->n++;
    c->touched = mono_now();
    if (line_out)
        sb_add(line_out, line.buf, line.len);
    line.buf = NULL;
    wake_all(h, c);
out:
    pthread_mutex_unlock(&h->lock);
    sb_free(&line);
    return seq;
}

void poll_end(poll_hub *h, const char *id)
{
    pthread_mutex_lock(&h->lock);
    poll_chan *c = find_or_add(h, id);
    if (c) {
        c->done = 1;
        c->touched = mono_now();
        wake_all(h, c);
    }
    pthread_mutex_unlock(&h->lock);
}

void poll_drop(poll_hub *h, const char *id)
{
    pthread_mutex_lock(&h->lock);
    for (poll_chan **pp = &h->chans; *pp; pp = &(*pp)->next) {
        if (!strcmp((*pp)->id, id)) {
            poll_chan *c = *pp;
            wake_all(h, c);
            *pp = c->next;
            free_chan(c);
            break;
        }
    }
    pthread_mutex_unlock(&h->lock);
}

int poll_read(poll_hub *h, const char *id, long after, sbuf *out, int *count, long *last,
              int *done)
{
    poll_chan *c;

    *count = 0;
    *last = -1;
    *done = 0;
    pthread_mutex_lock(&h->lock);
    c = find(h, id);
    if (c && !c->local)
        c = NULL; /* only parked readers: the records are elsewhere */
    if (c) {
        long start = after < 0 ? 0 : after >= c->n ? c->n : after + 1;
        for (long i = start; i < c->n; i++) {
            if (*count)
                sb_puts(out, ",");
            sb_add(out, c->rec[i], c->rlen[i]);
            (*count)++;
        }
        *last = c->n - 1;
        *done = c->done;
    }
    pthread_mutex_unlock(&h->lock);
    return c != NULL;
}

/* Was id kicked after gen? Hub lock held. Conservative: yes when the ring
 * no longer reaches back to gen. */
static int kicked_since(poll_hub *h, const char *id, unsigned long gen)
{
    if (h->kick_gen == gen)
        return 0;
    if (h->kick_all_gen > gen || h->kick_gen - gen >= KICK_RING)
        return 1;
    for (unsigned long k = gen + 1; k <= h->kick_gen; k++)
        if (!strcmp(h->ring[k % KICK_RING], id))
            return 1;
    return 0;
}

int poll_park(poll_hub *h, const char *id, long after, poll_waiter *w,
              struct MHD_Connection *conn, double deadline)
{
    return poll_park_since(h, id, after, w, conn, deadline, poll_kick_gen(h));
}

unsigned long poll_kick_gen(poll_hub *h)
{
    pthread_mutex_lock(&h->lock);
    unsigned long g = h->kick_gen;
    pthread_mutex_unlock(&h->lock);
    return g;
}

void poll_kick(poll_hub *h, const char *id)
{
    pthread_mutex_lock(&h->lock);
    h->kick_gen++;
    snprintf(h->ring[h->kick_gen % KICK_RING], sizeof h->ring[0], "%s", id);
    poll_chan *c = find(h, id);
    if (c && !c->local)
        wake_all(h, c);
    pthread_mutex_unlock(&h->lock);
}

void poll_kick_all(poll_hub *h)
{
    pthread_mutex_lock(&h->lock);
    h->kick_all_gen = ++h->kick_gen;
    h->ring[h->kick_gen % KICK_RING][0] = 0;
    for (poll_chan *c = h->chans; c; c = c->next)
        if (!c->local)
            wake_all(h, c);
    pthread_mutex_unlock(&h->lock);
}

int poll_park_since(poll_hub *h, const char *id, long after, poll_waiter *w,
                    struct MHD_Connection *conn, double deadline, unsigned long gen)
{
    int parked = 0;
    poll_chan *c;
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CONNECTION_FD);

    w->fd = ci ? ci->connect_fd : -1;
    w->gone = 0;
    pthread_mutex_lock(&h->lock);
    if (h->shutting_down)
        goto out;
    c = find_or_add(h, id);
    if (!c || c->done || c->n - 1 > after || (!c->local && kicked_since(h, id, gen)))
        goto out;
    w->chan = c;
    w->conn = conn;
    w->deadline = deadline;
    w->prev = NULL;
    w->next = c->waiters;
    if (c->waiters)
        c->waiters->prev = w;
    c->waiters = w;
    w->parked = 1;
    c->touched = mono_now();
    h->nparked++;
    MHD_suspend_connection(conn);
    pthread_cond_signal(&h->cond); /* the timer may need to wake earlier */
    parked = 1;
out:
    pthread_mutex_unlock(&h->lock);
    return parked;
}

int poll_parked_count(poll_hub *h)
{
    pthread_mutex_lock(&h->lock);
    int n = h->nparked;
    pthread_mutex_unlock(&h->lock);
    return n;
}

long poll_gone_count(poll_hub *h)
{
    pthread_mutex_lock(&h->lock);
    long n = h->ngone;
    pthread_mutex_unlock(&h->lock);
    return n;
}

int poll_shutting_down(poll_hub *h)
{
    pthread_mutex_lock(&h->lock);
    int s = h->shutting_down;
    pthread_mutex_unlock(&h->lock);
    return s;
}
