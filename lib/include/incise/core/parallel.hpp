#pragma once
/// \file parallel.hpp
/// Element-loop threading (issue 19; docs/fem_performance.md "Element loops on T threads"): one
/// process-wide pool of persistent worker threads, and a fixed schedule of work chunks whose
/// results do not depend on how many threads run it.
///
/// Determinism contract: a ChunkSchedule is built from the work alone (which chunk touches which
/// shared resource, e.g. which mesh node), never from a thread count. Chunks that touch a common
/// resource get different colours and run in colour order; chunks of one colour touch disjoint
/// resources. So every resource receives its contributions in one fixed order — colour, then
/// the order inside the chunk — whichever thread runs a chunk and however many there are, and
/// the arithmetic (hence every bit of the result) is the same for every thread count.
///
/// Idle workers block on a condition variable (they never spin between calls). A second
/// concurrent run_parallel()/run_chunks() — from another thread, or nested inside a participant
/// — does not wait for the pool: it runs on its calling thread alone (same results, by the
/// contract above).

#include <incise/core/types.hpp>

#include <functional>
#include <vector>

namespace incise {

/// Largest accepted thread count (INCISE_THREADS, scene key "threads").
inline constexpr int kMaxThreads = 256;

/// Parses a thread count: `value` (INCISE_THREADS, an integer from 1 to kMaxThreads, or null
/// when unset) or, when null, `available` (clamped to [1, kMaxThreads]). Throws ParameterError
/// naming INCISE_THREADS and the value for anything else ("0", "2x", "-1", "").
int parse_thread_count(const char* value, int available);

/// The process default for element loops: parse_thread_count(getenv("INCISE_THREADS"),
/// std::thread::hardware_concurrency()) — all cores unless the variable says otherwise. Read once
/// (first call); throws ParameterError (every call) when the variable is malformed.
int default_thread_count();

/// Runs `participant()` on `threads` threads at once — the caller and threads − 1 pool workers
/// (created on first need and kept) — and returns when all have returned. Each participant is
/// expected to claim work itself (e.g. from an atomic counter). Runs on the caller alone when
/// threads ≤ 1 or the pool is busy (see file comment). Returns the number of participants. The
/// first exception a participant throws is rethrown here after all have finished.
int run_parallel(int threads, const std::function<void()>& participant);

/// A fixed order of work chunks with conflicts resolved by colour (see file comment).
struct ChunkSchedule {
  std::vector<int> order;       ///< chunks in claiming order: by colour, then chunk index
  std::vector<int> colour;      ///< colour of each chunk (greedy, chunk-index order)
  std::vector<int> pred_start;  ///< CSR: predecessors of chunk c are preds[pred_start[c] ...
  std::vector<int> preds;       ///<   pred_start[c + 1]): conflicting chunks of a lower colour
  int num_colours = 0;
  int num_chunks() const { return static_cast<int>(colour.size()); }
};

/// Builds the schedule of `chunk_start.size() − 1` chunks from the resources each touches:
/// chunk c touches resources[chunk_start[c] … chunk_start[c + 1]) (duplicates allowed), each in
/// [0, num_resources). Two chunks conflict when they share a resource. Throws UsageError for a
/// malformed CSR or a resource out of range.
ChunkSchedule make_chunk_schedule(const std::vector<Index>& chunk_start,
                                  const std::vector<Index>& resources, Index num_resources);

/// Calls fn(c) once for every chunk of `schedule`, on up to `threads` threads (run_parallel):
/// chunks are claimed in schedule.order and a chunk starts only after its predecessors have
/// finished, so conflicting chunks never overlap and run in colour order. fn must not throw.
void run_chunks(const ChunkSchedule& schedule, int threads, const std::function<void(int)>& fn);

}  // namespace incise
