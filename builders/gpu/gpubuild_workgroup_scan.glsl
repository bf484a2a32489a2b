// A prelude: the exclusive prefix sum of one value per invocation over a workgroup of 256, for the
// radix sort's scans (gpubuild_radix_scan.glsl, gpubuild_radix_scatter.glsl). Sixteen invocations
// each scan a run of 16 values, one scans the 16 runs' sums: 4 barriers where Hillis-Steele takes 16.
// The serial runs cost a few hundred cycles on a GPU; on llvmpipe, which switches between a
// workgroup's invocations at every barrier, the barriers are what a scan costs.
shared uint s_scanValues[256];
shared uint s_scanRuns[16];
shared uint s_scanTotal;

// Called by every invocation of the workgroup, in uniform control flow (it holds barriers), with
// t = gl_LocalInvocationID.x < 256. Returns the sum of the lower invocations' values; `total` is the
// whole workgroup's. It may be called again at once (its last barrier ends its reads).
uint workgroupExclusiveSum(uint t, uint value, out uint total) {
  s_scanValues[t] = value;
  barrier();
  if (t < 16u) {
    uint sum = 0u;
    for (uint k = 16u * t; k < 16u * t + 16u; ++k) {
      uint v = s_scanValues[k];
      s_scanValues[k] = sum;
      sum += v;
    }
    s_scanRuns[t] = sum;
  }
  barrier();
  if (t == 0u) {
    uint sum = 0u;
    for (uint k = 0u; k < 16u; ++k) {
      uint v = s_scanRuns[k];
      s_scanRuns[k] = sum;
      sum += v;
    }
    s_scanTotal = sum;
  }
  barrier();
  uint before = s_scanRuns[t >> 4u] + s_scanValues[t];
  total = s_scanTotal;
  barrier();
  return before;
}
