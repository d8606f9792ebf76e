/*
 * soem_cycle: a minimal cyclic EtherCAT master on SOEM, the third baseline of
 * `ecdrive jitter` (src/app/harness/soem.rs runs it and reads what it writes).
 *
 * It configures the segment the way a SOEM application does: ec_config_init, the PRE-OP
 * SDO writes the harness passes (--sdo, taken from each drive's profile), DC with SYNC0 on
 * every DC device, ec_config_map, SAFE-OP, then cycles process data until every device is in
 * OP (not measured), then measures --cycles cycles. Its wake-ups are steered to the
 * reference clock so that each frame leaves at SYNC0 + shift, as ethercrab's tx_rx_dc and
 * ecdrive's cycle do: SYNC0 fires on whole multiples of the cycle in system time
 * (ec_dcsync0 with shift 0 rounds the start up to a multiple of the cycle, 100 ms ahead), the
 * frame carries the reference clock's time (SOEM adds a FRMW of 0x0910 to the process data
 * frame of a DC group), and a small proportional-integral term moves the next wake-up by the
 * phase error.
 *
 * Output: the measured cycles to --samples as little-endian u32 quadruples (wake-up latency,
 * period, round trip, busy; ns), and key=value lines on stdout. Exit codes: 2 bad arguments,
 * 3 interface, 4 device count, 5 not in OP in time, 6 other failures; one line on stderr.
 *
 * Written for this benchmark; built by build.sh from the SOEM sources of the pysoem source
 * distribution. Not part of ecdrive.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <inttypes.h>
#include <pthread.h>
#include <sched.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <time.h>

#include "ethercat.h"

#define MAX_ITEMS 8192

static uint8 IOmap[1 << 16];

/* SOEM's state, in a context of this program's own (SOEM built with EC_VER2, as pysoem
 * builds it: only the ecx_ functions). */
static ecx_portt port;
static ec_slavet slaves[EC_MAXSLAVE];
static int slavecount;
static ec_groupt groups[EC_MAXGROUP];
static uint8 esibuf[EC_MAXEEPBUF];
static uint32 esimap[EC_MAXEEPBITMAP];
static ec_eringt elist;
static ec_idxstackT idxstack;
static boolean ecaterror;
static int64 dc_time;
static ec_SMcommtypet smcommtype[EC_MAX_MAPT];
static ec_PDOassignt pdoassign[EC_MAX_MAPT];
static ec_PDOdesct pdodesc[EC_MAX_MAPT];
static ec_eepromSMt eep_sm;
static ec_eepromFMMUt eep_fmmu;
static ecx_contextt ctx = {
    .port = &port,
    .slavelist = &slaves[0],
    .slavecount = &slavecount,
    .maxslave = EC_MAXSLAVE,
    .grouplist = &groups[0],
    .maxgroup = EC_MAXGROUP,
    .esibuf = &esibuf[0],
    .esimap = &esimap[0],
    .elist = &elist,
    .idxstack = &idxstack,
    .ecaterror = &ecaterror,
    .DCtime = &dc_time,
    .SMcommtype = &smcommtype[0],
    .PDOassign = &pdoassign[0],
    .PDOdesc = &pdodesc[0],
    .eepSM = &eep_sm,
    .eepFMMU = &eep_fmmu,
};

struct sdo_write {
    int pos;
    uint16 index;
    uint8 sub;
    int size;
    uint32 value;
};
struct out_field {
    int pos;
    int byte;
    int size;
    int64_t value;
};

static struct sdo_write sdos[MAX_ITEMS];
static int n_sdos;
static struct out_field defaults[MAX_ITEMS];
static int n_defaults;
static struct out_field counters[MAX_ITEMS];
static int n_counters;

static void fail(int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("soem_cycle: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    exit(code);
}

static uint64_t clock_ns(clockid_t c)
{
    struct timespec t;
    clock_gettime(c, &t);
    return (uint64_t)t.tv_sec * 1000000000ull + (uint64_t)t.tv_nsec;
}

static uint64_t now_ns(void) { return clock_ns(CLOCK_MONOTONIC); }

static void sleep_until(uint64_t ns)
{
    struct timespec t = {.tv_sec = (time_t)(ns / 1000000000ull),
                         .tv_nsec = (long)(ns % 1000000000ull)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, NULL) == EINTR) {
    }
}

static long long number(const char *arg, const char *s)
{
    char *end = NULL;
    errno = 0;
    long long v = strtoll(s, &end, 0);
    if (errno || end == s || *end != '\0')
        fail(2, "%s: %s is not a number", arg, s);
    return v;
}

/* Split "a:b:c" into at most n numbers. */
static int fields(const char *arg, const char *s, long long *out, int n)
{
    char buf[256];
    if (strlen(s) >= sizeof buf)
        fail(2, "%s: %s is too long", arg, s);
    strcpy(buf, s);
    int k = 0;
    for (char *tok = strtok(buf, ":"); tok; tok = strtok(NULL, ":")) {
        if (k == n)
            fail(2, "%s: %s has more than %d fields", arg, s, n);
        out[k++] = number(arg, tok);
    }
    return k;
}

static void check_size(const char *arg, long long size)
{
    if (size != 1 && size != 2 && size != 4)
        fail(2, "%s: size %lld is not 1, 2 or 4", arg, size);
}

static void put_le(uint8 *p, int size, int64_t v)
{
    for (int i = 0; i < size; i++)
        p[i] = (uint8)((uint64_t)v >> (8 * i));
}

/* The phase error of a reference clock time against the frame's intended instant
 * (shift after a SYNC0 on the cycle grid), in [-cycle/2, cycle/2). */
static int64_t phase_error(int64_t dc, int64_t cycle, int64_t shift)
{
    int64_t e = (dc - shift) % cycle;
    if (e < 0)
        e += cycle;
    if (e >= cycle / 2)
        e -= cycle;
    return e;
}

static const char *state_name(uint16 s)
{
    switch (s & 0x0F) {
    case EC_STATE_INIT: return "INIT";
    case EC_STATE_PRE_OP: return "PRE-OP";
    case EC_STATE_BOOT: return "BOOT";
    case EC_STATE_SAFE_OP: return "SAFE-OP";
    case EC_STATE_OPERATIONAL: return "OP";
    default: return "unknown";
    }
}

struct sample {
    uint32_t wake, period, exchange, busy;
};

static uint32_t sat32(uint64_t v) { return v > UINT32_MAX ? UINT32_MAX : (uint32_t)v; }

int main(int argc, char **argv)
{
    const char *ifname = NULL, *samples_path = NULL;
    long long expect = -1, cycle_ns = 0, cycles = 0, shift_ns = -1, priority = 0, cpu = -1;
    long long op_timeout_ms = 10000;
    double budget = 0.8;
    int lock_memory = 0;

    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = (i + 1 < argc) ? argv[i + 1] : NULL;
        long long f[5];
        if (!strcmp(a, "--lock-memory")) {
            lock_memory = 1;
            continue;
        }
        if (!v)
            fail(2, "%s: missing value (or unknown argument)", a);
        i++;
        if (!strcmp(a, "--interface")) ifname = v;
        else if (!strcmp(a, "--samples")) samples_path = v;
        else if (!strcmp(a, "--expect")) expect = number(a, v);
        else if (!strcmp(a, "--cycle-ns")) cycle_ns = number(a, v);
        else if (!strcmp(a, "--cycles")) cycles = number(a, v);
        else if (!strcmp(a, "--shift-ns")) shift_ns = number(a, v);
        else if (!strcmp(a, "--priority")) priority = number(a, v);
        else if (!strcmp(a, "--cpu")) cpu = number(a, v);
        else if (!strcmp(a, "--op-timeout-ms")) op_timeout_ms = number(a, v);
        else if (!strcmp(a, "--budget")) {
            char *end = NULL;
            budget = strtod(v, &end);
            if (end == v || *end || budget <= 0 || budget > 1)
                fail(2, "--budget: %s is not a fraction in (0, 1]", v);
        } else if (!strcmp(a, "--sdo")) {
            if (fields(a, v, f, 5) != 5)
                fail(2, "--sdo: %s is not POS:INDEX:SUB:SIZE:VALUE", v);
            check_size(a, f[3]);
            if (n_sdos == MAX_ITEMS) fail(2, "--sdo: too many");
            sdos[n_sdos++] = (struct sdo_write){(int)f[0], (uint16)f[1], (uint8)f[2], (int)f[3],
                                                (uint32)f[4]};
        } else if (!strcmp(a, "--default")) {
            if (fields(a, v, f, 4) != 4)
                fail(2, "--default: %s is not POS:BYTE:SIZE:VALUE", v);
            check_size(a, f[2]);
            if (n_defaults == MAX_ITEMS) fail(2, "--default: too many");
            defaults[n_defaults++] = (struct out_field){(int)f[0], (int)f[1], (int)f[2], f[3]};
        } else if (!strcmp(a, "--counter")) {
            if (fields(a, v, f, 2) != 2)
                fail(2, "--counter: %s is not POS:BYTE", v);
            if (n_counters == MAX_ITEMS) fail(2, "--counter: too many");
            counters[n_counters++] = (struct out_field){(int)f[0], (int)f[1], 1, 0};
        } else
            fail(2, "unknown argument %s", a);
    }
    if (!ifname || !samples_path || expect < 1 || cycle_ns < 10000 || cycles < 1 || shift_ns < 0 ||
        shift_ns >= cycle_ns)
        fail(2, "needs --interface, --samples, --expect N>0, --cycle-ns >= 10000, --cycles N>0 "
                "and --shift-ns within the cycle");

    uint64_t t_start = now_ns();
    if (!ecx_init(&ctx, ifname))
        fail(3, "opening %s: ec_init failed (no such interface, or no permission)", ifname);
    int found = ecx_config_init(&ctx, FALSE);
    if (found != expect)
        fail(4, "found %d devices on %s, expected %lld", found, ifname, expect);
    ecx_statecheck(&ctx, 0, EC_STATE_PRE_OP, EC_TIMEOUTSTATE);

    /* The drives' PRE-OP configuration, as the harness gives it. */
    for (int i = 0; i < n_sdos; i++) {
        struct sdo_write *s = &sdos[i];
        if (s->pos < 0 || s->pos >= found)
            fail(2, "--sdo: position %d is not on the segment", s->pos);
        uint8 data[4];
        put_le(data, s->size, s->value);
        int wkc = ecx_SDOwrite(&ctx, (uint16)(s->pos + 1), s->index, s->sub, FALSE, s->size, data,
                              EC_TIMEOUTRXM);
        if (wkc <= 0)
            fail(6, "device %d: SDO download 0x%04X:%02X (%d bytes, %" PRIu32 ") failed: %s",
                 s->pos, s->index, s->sub, s->size, s->value,
                 ecx_iserror(&ctx) ? ecx_elist2string(&ctx) : "no answer");
    }

    /* DC: propagation delays and offsets, then SYNC0 on every DC device on the cycle grid
     * (the frames go out shift after it). */
    ecx_configdc(&ctx);
    for (int i = 1; i <= found; i++)
        if (slaves[i].hasdc)
            ecx_dcsync0(&ctx, (uint16)i, TRUE, (uint32)cycle_ns, 0);
    uint64_t sync0_from = now_ns() + 100000000ull;

    int iomap = ecx_config_map_group(&ctx, IOmap, 0);
    if (iomap > (int)sizeof IOmap)
        fail(6, "the process image (%d bytes) is larger than %zu", iomap, sizeof IOmap);
    slaves[0].state = EC_STATE_SAFE_OP;
    ecx_writestate(&ctx, 0);
    if (ecx_statecheck(&ctx, 0, EC_STATE_SAFE_OP, EC_TIMEOUTSTATE * 4) != EC_STATE_SAFE_OP) {
        ecx_readstate(&ctx);
        for (int i = 1; i <= found; i++)
            if ((slaves[i].state & 0x0F) != EC_STATE_SAFE_OP)
                fail(5, "device %d is in %s (AL status code 0x%04X), not SAFE-OP", i - 1,
                     state_name(slaves[i].state), slaves[i].ALstatuscode);
        fail(5, "the segment did not reach SAFE-OP");
    }
    int expected_wkc = groups[0].outputsWKC * 2 + groups[0].inputsWKC;
    for (int i = 0; i < n_defaults; i++) {
        struct out_field *d = &defaults[i];
        if (d->pos < 0 || d->pos >= found || d->byte + d->size > (int)slaves[d->pos + 1].Obytes)
            fail(2, "--default: %d:%d does not fit device %d's outputs", d->pos, d->byte, d->pos);
        put_le(slaves[d->pos + 1].outputs + d->byte, d->size, d->value);
    }
    for (int i = 0; i < n_counters; i++) {
        struct out_field *c = &counters[i];
        if (c->pos < 0 || c->pos >= found || c->byte >= (int)slaves[c->pos + 1].Obytes)
            fail(2, "--counter: %d:%d does not fit device %d's outputs", c->pos, c->byte, c->pos);
    }

    /* Real-time set-up of this thread, as the other runs get it. */
    int granted = 0, pinned = 0, locked = 0;
    if (priority > 0) {
        struct sched_param p = {.sched_priority = (int)priority};
        if (pthread_setschedparam(pthread_self(), SCHED_FIFO, &p) == 0)
            granted = (int)priority;
        else
            printf("warning=real-time priority SCHED_FIFO %lld not granted\n", priority);
    }
    if (cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET((int)cpu, &set);
        if (pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0)
            pinned = 1;
        else
            printf("warning=pinning to CPU %lld failed\n", cpu);
    }
    if (lock_memory) {
        if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0)
            locked = 1;
        else
            printf("warning=memory not locked (mlockall failed)\n");
    }

    struct sample *samples = calloc((size_t)cycles, sizeof *samples);
    if (!samples)
        fail(6, "no memory for %lld samples", cycles);
    memset(samples, 0, (size_t)cycles * sizeof *samples); /* touch every page before the window */

    const int64_t cyc = cycle_ns, shift = shift_ns;
    const uint64_t budget_ns = (uint64_t)(budget * (double)cycle_ns);
    int timeout_us = (int)(budget_ns / 1000);
    if (timeout_us < 1)
        timeout_us = 1;
    int64_t integral = 0;
    uint8 counter = 0;
    uint64_t next = now_ns() + (uint64_t)cyc;
    uint64_t op_deadline = now_ns() + (uint64_t)op_timeout_ms * 1000000ull;
    int op_requested = 0;
    uint64_t op_at = 0;
    long long k = -1; /* measured cycle index; -1: not yet */
    uint64_t last_wake = 0, cpu_p0 = 0, cpu_t0 = 0;
    struct rusage ru0;
    long long late = 0, missed = 0, wkc_errors = 0;
    unsigned settle = 0;

    for (;;) {
        const uint64_t target = next;
        sleep_until(target);
        const uint64_t woke = now_ns();
        const uint64_t t0 = now_ns();
        ecx_send_processdata(&ctx);
        const int wkc = ecx_receive_processdata(&ctx, timeout_us);
        const uint64_t t1 = now_ns();
        /* The application's part: read each device's inputs, advance the counters. */
        for (int i = 1; i <= found; i++)
            if (slaves[i].Ibytes)
                (void)*(volatile uint8 *)slaves[i].inputs;
        counter++;
        for (int i = 0; i < n_counters; i++)
            slaves[counters[i].pos + 1].outputs[counters[i].byte] = counter;
        const int answered = wkc > 0;
        if (answered) {
            const int64_t e = phase_error(dc_time, cyc, shift);
            integral += e;
            if (integral > cyc * 64) integral = cyc * 64;
            if (integral < -cyc * 64) integral = -cyc * 64;
            int64_t corr = e / 8 + integral / 512;
            if (corr > cyc / 4) corr = cyc / 4;
            if (corr < -cyc / 4) corr = -cyc / 4;
            next = target + (uint64_t)(cyc - corr);
        } else {
            next = target + (uint64_t)cyc;
        }
        while (next <= woke)
            next += (uint64_t)cyc; /* fell behind by whole cycles: those count as late */

        if (k >= 0) {
            struct sample *s = &samples[k];
            const uint64_t latency = woke > target ? woke - target : 0;
            s->wake = sat32(latency);
            s->period = last_wake ? sat32(woke - last_wake) : 0;
            s->exchange = sat32(t1 - t0);
            if (latency > (uint64_t)cyc)
                late++;
            if (!answered || wkc < expected_wkc || t1 - woke > budget_ns)
                missed++;
            if (answered && wkc < expected_wkc)
                wkc_errors++;
            last_wake = woke;
            s->busy = sat32(now_ns() - woke);
            if (++k == cycles)
                break;
            continue;
        }

        /* Not measured: bring the segment to OP once SYNC0 runs. */
        if (!op_requested) {
            if (now_ns() > sync0_from + 10 * (uint64_t)cyc && ++settle > 10) {
                slaves[0].state = EC_STATE_OPERATIONAL;
                ecx_writestate(&ctx, 0);
                op_requested = 1;
            }
        } else if ((counter % 16) == 0 && ecx_readstate(&ctx) == EC_STATE_OPERATIONAL) {
            /* The window opens with the next wake-up. */
            op_at = now_ns();
            k = 0;
            last_wake = 0;
            cpu_p0 = clock_ns(CLOCK_PROCESS_CPUTIME_ID);
            cpu_t0 = clock_ns(CLOCK_THREAD_CPUTIME_ID);
            getrusage(RUSAGE_THREAD, &ru0);
            continue;
        }
        if (now_ns() > op_deadline) {
            ecx_readstate(&ctx);
            for (int i = 1; i <= found; i++)
                if ((slaves[i].state & 0x0F) != EC_STATE_OPERATIONAL)
                    fail(5, "device %d is in %s (AL status code 0x%04X), not OP after %lld ms",
                         i - 1, state_name(slaves[i].state), slaves[i].ALstatuscode,
                         op_timeout_ms);
            fail(5, "the segment did not reach OP in %lld ms", op_timeout_ms);
        }
    }
    const uint64_t cpu_p1 = clock_ns(CLOCK_PROCESS_CPUTIME_ID);
    const uint64_t cpu_t1 = clock_ns(CLOCK_THREAD_CPUTIME_ID);
    struct rusage ru1;
    getrusage(RUSAGE_THREAD, &ru1);

    FILE *f = fopen(samples_path, "wb");
    if (!f)
        fail(6, "writing %s: %s", samples_path, strerror(errno));
    for (long long i = 0; i < cycles; i++) {
        uint8 b[16];
        put_le(b, 4, samples[i].wake);
        put_le(b + 4, 4, samples[i].period);
        put_le(b + 8, 4, samples[i].exchange);
        put_le(b + 12, 4, samples[i].busy);
        if (fwrite(b, 1, sizeof b, f) != sizeof b)
            fail(6, "writing %s: %s", samples_path, strerror(errno));
    }
    if (fclose(f) != 0)
        fail(6, "writing %s: %s", samples_path, strerror(errno));

    printf("cycles=%lld\nlate=%lld\nmissed=%lld\nwkc_errors=%lld\nexpected_wkc=%d\n", cycles,
           late, missed, wkc_errors, expected_wkc);
    printf("op_ms=%.3f\n", (double)(op_at - t_start) / 1e6);
    printf("process_cpu_ns=%" PRIu64 "\nthread_cpu_ns=%" PRIu64 "\n", cpu_p1 - cpu_p0,
           cpu_t1 - cpu_t0);
    printf("voluntary_switches=%ld\ninvoluntary_switches=%ld\n", ru1.ru_nvcsw - ru0.ru_nvcsw,
           ru1.ru_nivcsw - ru0.ru_nivcsw);
    printf("priority_granted=%d\ncpu_pinned=%d\nmemory_locked=%d\ndevices=%d\n", granted, pinned,
           locked, found);
    printf("soem_version=1.4 (pysoem 1.1.13 source distribution)\n");

    /* Back to INIT. */
    slaves[0].state = EC_STATE_INIT;
    ecx_writestate(&ctx, 0);
    ecx_close(&ctx);
    free(samples);
    return 0;
}
