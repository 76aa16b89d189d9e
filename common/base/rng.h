/* rng.h: PCG32 (O'Neill 2014), the only random source of the renderer. A stream is keyed by
 * (job seed, iteration, purpose, index) so an iteration renders identically on any machine,
 * with any thread count. */
#ifndef PC_RNG_H
#define PC_RNG_H

#include <stdint.h>

typedef struct pc_rng { uint64_t state, inc; } pc_rng;

static inline uint64_t pc_splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

static inline uint32_t pc_rng_u32(pc_rng *r) {
  uint64_t old = r->state;
  r->state = old * 6364136223846793005ull + r->inc;
  uint32_t xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
  uint32_t rot = (uint32_t)(old >> 59u);
  return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
}

/* Uniform in [0, 1): 24 random bits so the result is exactly representable and < 1. */
static inline float pc_rng_f(pc_rng *r) { return (float)(pc_rng_u32(r) >> 8) * 0x1p-24f; }

/* Purposes keep streams of different kinds of paths apart. */
enum { PC_STREAM_EYE = 1, PC_STREAM_LIGHT = 2, PC_STREAM_CACHE = 3, PC_STREAM_CONNECT = 4, PC_STREAM_MISC = 5, PC_STREAM_TIME = 6, PC_STREAM_LENS = 7 };

static inline pc_rng pc_rng_make(uint64_t seed, uint64_t iteration, uint32_t purpose, uint64_t index) {
  pc_rng r;
  uint64_t a = pc_splitmix64(seed ^ pc_splitmix64(iteration + 0x632be59bd9b4e019ull));
  uint64_t b = pc_splitmix64(a ^ ((uint64_t)purpose << 56) ^ pc_splitmix64(index));
  r.state = 0u;
  r.inc = (pc_splitmix64(b ^ 0xda942042e4dd58b5ull) << 1u) | 1u;
  pc_rng_u32(&r);
  r.state += b;
  pc_rng_u32(&r);
  return r;
}

#endif
