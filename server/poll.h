/* poll.h - progress channels and parked connections (long-poll and SSE).
 * A channel per job holds the progress records of its current run, in order
 * (record k has "seq": k). Readers that find nothing new park: their MHD
 * connection is suspended and linked to the channel, costing no thread. A
 * worker publishing a record, the end of a run, the waiter's deadline (one
 * timer thread for all) or shutdown resumes them; MHD then calls the handler
 * (or the SSE content reader) again, which re-reads and answers or parks again.
 * MHD does not watch a suspended connection's socket, so the timer thread also
 * polls the parked sockets every second: a client that hung up is resumed with
 * `gone` set, and the handler drops the connection.
 * Several nodes (PostgreSQL store): a job running on another node has no
 * records here; readers take them from the database and park on the job's
 * channel, and the node's listener (LISTEN/NOTIFY) kicks the channel when the
 * other node writes a record or the job changes state. A kick that lands
 * between a reader's database read and its park is not lost: the reader
 * takes poll_kick_gen() before reading and parks with poll_park_since, which
 * refuses when the channel was kicked since.
 * All functions are thread-safe. */
#ifndef QDCD_POLL_H
#define QDCD_POLL_H

#include "util.h"

#include <microhttpd.h>

struct poll_chan;

/* Lives inside the request; linked while parked. */
typedef struct poll_waiter {
    struct poll_waiter *next, *prev;
    struct poll_chan *chan;
    struct MHD_Connection *conn;
    double deadline; /* mono_now() seconds */
    int parked;      /* 1 while suspended and linked */
    int fd;          /* the connection's socket, watched while parked */
    int gone;        /* resumed because the client closed it: answer nothing */
} poll_waiter;

typedef struct poll_hub poll_hub;

poll_hub *poll_new(void);
/* Start the deadline thread. 0 or -1. */
int poll_start(poll_hub *h);
/* Resume every parked connection and refuse new parks (shutdown, step 1). */
void poll_shutdown(poll_hub *h);
/* Stop the deadline thread and free (after the HTTP daemon stopped). */
void poll_free(poll_hub *h);

/* Worker side. begin: a run starts (records cleared); publish: append one record
 * (JSON object without the seq member, which is added); end: the run is over,
 * the channel stays readable for a while. publish returns the record's seq. */
void poll_begin(poll_hub *h, const char *id);
long poll_publish(poll_hub *h, const char *id, const char *json, size_t len,
                  sbuf *line_out);
void poll_end(poll_hub *h, const char *id);
/* Forget a channel (job deleted): waiters are resumed first. */
void poll_drop(poll_hub *h, const char *id);

/* Reader side. Appends the records with seq > after to out, comma-separated;
 * *count, *last (seq of the last record of the run, -1 if none) and *done
 * (the run ended) are set. Returns 0 if there is no channel for id with a
 * run of this process (begin or publish was called for it). */
int poll_read(poll_hub *h, const char *id, long after, sbuf *out, int *count, long *last,
              int *done);
/* Atomically: if there is nothing after `after`, the channel is not done and
 * the hub is not shutting down, link w (creating the channel), suspend c and
 * return 1; else return 0 (answer now). Called from the MHD thread only. */
int poll_park(poll_hub *h, const char *id, long after, poll_waiter *w,
              struct MHD_Connection *c, double deadline);
/* As poll_park, and also refuses when id was kicked after gen (a value of
 * poll_kick_gen taken before the reader read the records it has). */
int poll_park_since(poll_hub *h, const char *id, long after, poll_waiter *w,
                    struct MHD_Connection *c, double deadline, unsigned long gen);
unsigned long poll_kick_gen(poll_hub *h);
/* Another node changed id (a record, a state): resume its parked readers,
 * unless the run is this process's (its own publish/end wake them). */
void poll_kick(poll_hub *h, const char *id);
/* Anything may have changed (the listener reconnected): resume every
 * parked reader of a run that is not this process's. */
void poll_kick_all(poll_hub *h);
int poll_parked_count(poll_hub *h);
/* Parked connections resumed because their client had closed them. */
long poll_gone_count(poll_hub *h);
int poll_shutting_down(poll_hub *h);

#endif
