/* range_size.c: the size of a fresh iteration range (see range_size.h). */
#include "range_size.h"

#include "wire_upload.h"

uint64_t pc_range_size(const pc_range_size_in *in) {
  double n;
  if (!(in->rate > 0)) {
    if (!in->alone || !in->bounded || in->interleaved) return 1; /* a probe */
    n = (double)in->unassigned;
  } else {
    double pay = pc_wire_upload_spacing(in->upload_seconds, PC_WIRE_UPLOAD_SHARE);
    n = in->rate * (in->range_seconds > pay ? in->range_seconds : pay);
    if (in->bounded) {
      double others = in->others_rate > 0 ? in->others_rate : 0;
      double left = (double)in->unassigned + (in->outstanding > 0 ? in->outstanding : 0);
      double share = left * in->rate / (in->rate + others);
      double floor_n = in->rate * (PC_RANGE_MIN_SECONDS > pay ? PC_RANGE_MIN_SECONDS : pay);
      double want = in->alone ? share : 0.5 * share;
      if (want < floor_n) want = floor_n < share ? floor_n : share;
      if (n > want) n = want;
    }
  }
  uint64_t k = n < 1 ? 1 : n > 1e6 ? 1000000 : (uint64_t)n;
  if (in->bounded && in->interleaved) {
    uint64_t turn = (in->interleaved + PC_RANGE_INTERLEAVE - 1) / PC_RANGE_INTERLEAVE;
    if (k > turn) k = turn;
  }
  if (in->bounded && k > in->unassigned) k = in->unassigned;
  return k < 1 ? 1 : k;
}
