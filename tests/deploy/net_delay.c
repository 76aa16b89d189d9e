/* net_delay.c: delays the packets of one netfilter queue by D +- J milliseconds (uniform),
 * standing in for netem's delay where the kernel has no sch_netem. iptables sends packets to
 * the queue (-j NFQUEUE --queue-num N --queue-bypass, so traffic flows if this dies); the
 * verdict of each is held back until its release time. Stops by itself after --seconds.
 *   net_delay --queue N --delay-ms D --jitter-ms J --seconds S */
#include <arpa/inet.h>
#include <errno.h>
#include <libnetfilter_queue/libnetfilter_queue.h>
#include <linux/netfilter.h>
#include <poll.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_HELD 65536

typedef struct held {
  uint64_t due_ns;
  uint32_t id;
} held;

typedef struct delayer {
  struct nfq_q_handle *qh;
  held heap[MAX_HELD]; /* min-heap on due_ns */
  int n;
  uint64_t delay_ns, jitter_ns;
  uint64_t rng;
  unsigned long long passed, overflowed;
} delayer;

static uint64_t now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec;
}

static uint64_t next_rand(delayer *d) { /* xorshift64*: jitter needs no more */
  d->rng ^= d->rng >> 12;
  d->rng ^= d->rng << 25;
  d->rng ^= d->rng >> 27;
  return d->rng * 2685821657736338717ull;
}

static void heap_push(delayer *d, held h) {
  int i = d->n++;
  while (i > 0 && d->heap[(i - 1) / 2].due_ns > h.due_ns) {
    d->heap[i] = d->heap[(i - 1) / 2];
    i = (i - 1) / 2;
  }
  d->heap[i] = h;
}

static held heap_pop(delayer *d) {
  held top = d->heap[0], last = d->heap[--d->n];
  int i = 0;
  for (;;) {
    int c = 2 * i + 1;
    if (c >= d->n) break;
    if (c + 1 < d->n && d->heap[c + 1].due_ns < d->heap[c].due_ns) c++;
    if (d->heap[c].due_ns >= last.due_ns) break;
    d->heap[i] = d->heap[c];
    i = c;
  }
  if (d->n > 0) d->heap[i] = last;
  return top;
}

static int on_packet(struct nfq_q_handle *qh, struct nfgenmsg *msg, struct nfq_data *nfa, void *data) {
  (void)msg;
  delayer *d = data;
  struct nfqnl_msg_packet_hdr *ph = nfq_get_msg_packet_hdr(nfa);
  if (!ph) return 0;
  uint32_t id = ntohl(ph->packet_id);
  if (d->n == MAX_HELD) { /* never hold more than the heap: let it through undelayed */
    d->overflowed++;
    return nfq_set_verdict(qh, id, NF_ACCEPT, 0, NULL) < 0 ? -1 : 0;
  }
  uint64_t j = d->jitter_ns ? next_rand(d) % (2 * d->jitter_ns + 1) : 0;
  heap_push(d, (held){now_ns() + d->delay_ns - d->jitter_ns + j, id});
  return 0;
}

static long arg(int argc, char **argv, const char *name, long lo, long hi) {
  for (int i = 1; i + 1 < argc; i += 2)
    if (strcmp(argv[i], name) == 0) {
      char *end;
      errno = 0;
      long v = strtol(argv[i + 1], &end, 10);
      if (errno || *end || v < lo || v > hi) {
        fprintf(stderr, "net_delay: %s: '%s' is not %ld..%ld\n", name, argv[i + 1], lo, hi);
        exit(2);
      }
      return v;
    }
  fprintf(stderr, "usage: net_delay --queue N --delay-ms D --jitter-ms J --seconds S\n");
  exit(2);
}

int main(int argc, char **argv) {
  static delayer d;
  int queue = (int)arg(argc, argv, "--queue", 0, 65535);
  d.delay_ns = (uint64_t)arg(argc, argv, "--delay-ms", 0, 10000) * 1000000ull;
  d.jitter_ns = (uint64_t)arg(argc, argv, "--jitter-ms", 0, 10000) * 1000000ull;
  if (d.jitter_ns > d.delay_ns) { fprintf(stderr, "net_delay: jitter exceeds the delay\n"); return 2; }
  uint64_t end = now_ns() + (uint64_t)arg(argc, argv, "--seconds", 1, 86400) * 1000000000ull;
  d.rng = now_ns() | 1;
  struct nfq_handle *h = nfq_open();
  if (!h) { perror("net_delay: nfq_open"); return 1; }
  d.qh = nfq_create_queue(h, (uint16_t)queue, on_packet, &d);
  if (!d.qh) { perror("net_delay: nfq_create_queue"); nfq_close(h); return 1; }
  if (nfq_set_mode(d.qh, NFQNL_COPY_META, 0) < 0 || nfq_set_queue_maxlen(d.qh, MAX_HELD) < 0) {
    perror("net_delay: queue setup");
    nfq_destroy_queue(d.qh);
    nfq_close(h);
    return 1;
  }
  int fd = nfq_fd(h);
  char buf[65536] __attribute__((aligned));
  int rc = 0;
  for (uint64_t t = now_ns(); t < end; t = now_ns()) {
    while (d.n > 0 && d.heap[0].due_ns <= t) {
      held p = heap_pop(&d);
      if (nfq_set_verdict(d.qh, p.id, NF_ACCEPT, 0, NULL) < 0) { perror("net_delay: verdict"); rc = 1; goto out; }
      d.passed++;
    }
    uint64_t wait = d.n > 0 ? d.heap[0].due_ns - t : 100000000ull;
    struct pollfd pfd = {fd, POLLIN, 0};
    int pr = poll(&pfd, 1, (int)((wait + 999999) / 1000000));
    if (pr < 0 && errno != EINTR) { perror("net_delay: poll"); rc = 1; break; }
    if (pr > 0) {
      ssize_t n = recv(fd, buf, sizeof buf, MSG_DONTWAIT);
      if (n < 0 && errno == ENOBUFS) continue; /* the kernel dropped some: TCP resends them */
      if (n < 0 && errno != EAGAIN && errno != EINTR) { perror("net_delay: recv"); rc = 1; break; }
      if (n > 0) nfq_handle_packet(h, buf, (int)n);
    }
  }
out:
  while (d.n > 0) nfq_set_verdict(d.qh, heap_pop(&d).id, NF_ACCEPT, 0, NULL);
  fprintf(stderr, "net_delay: queue %d: %llu packets delayed, %llu passed undelayed (full)\n", queue, d.passed,
          d.overflowed);
  nfq_destroy_queue(d.qh);
  nfq_close(h);
  return rc;
}
