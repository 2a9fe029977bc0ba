#include <incise/core/error.hpp>
#include <incise/core/parallel.hpp>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace incise {

int parse_thread_count(const char* value, int available) {
  if (value == nullptr) return std::clamp(available, 1, kMaxThreads);
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(value, &end, 10);
  if (end == value || *end != '\0' || errno != 0 || v < 1 || v > kMaxThreads)
    throw ParameterError(std::string("INCISE_THREADS = \"") + value +
                         "\": expected an integer from 1 to " + std::to_string(kMaxThreads));
  return static_cast<int>(v);
}

int default_thread_count() {
  static const int available = static_cast<int>(std::thread::hardware_concurrency());
  static const char* const value = std::getenv("INCISE_THREADS");  // NOLINT(concurrency-mt-unsafe)
  return parse_thread_count(value, available);
}

namespace {

/// The process-wide pool: workers started on first need and kept, each blocked on `start_`
/// between calls. One call at a time (busy_); see parallel.hpp.
class Pool {
 public:
  ~Pool() {
    {
      const std::lock_guard<std::mutex> lock(mu_);
      stop_ = true;
    }
    start_.notify_all();
    for (std::thread& t : workers_) t.join();
  }

  int run(int threads, const std::function<void()>& participant) {
    bool expected = false;
    if (threads <= 1 || !busy_.compare_exchange_strong(expected, true)) {
      participant();
      return 1;
    }
    struct Release {
      std::atomic<bool>& b;
      ~Release() { b.store(false); }
    } release{busy_};
    const int helpers = std::min(threads, kMaxThreads) - 1;
    std::exception_ptr first;
    {
      std::unique_lock<std::mutex> lock(mu_);
      while (static_cast<int>(workers_.size()) < helpers) {
        const int index = static_cast<int>(workers_.size());
        workers_.emplace_back([this, index] { loop(index); });
      }
      job_ = &participant;
      active_ = helpers;
      pending_ = helpers;
      error_ = nullptr;
      ++generation_;
    }
    start_.notify_all();
    try {
      participant();
    } catch (...) {
      first = std::current_exception();
    }
    std::unique_lock<std::mutex> lock(mu_);
    done_.wait(lock, [this] { return pending_ == 0; });
    job_ = nullptr;
    if (!first) first = error_;
    error_ = nullptr;
    lock.unlock();
    if (first) std::rethrow_exception(first);
    return helpers + 1;
  }

 private:
  void loop(int index) {
    std::uint64_t seen = 0;
    std::unique_lock<std::mutex> lock(mu_);
    for (;;) {
      start_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      if (index >= active_) continue;  // not needed for this call
      const std::function<void()>* job = job_;
      lock.unlock();
      std::exception_ptr err;
      try {
        (*job)();
      } catch (...) {
        err = std::current_exception();
      }
      lock.lock();
      if (err && !error_) error_ = err;
      if (--pending_ == 0) done_.notify_one();
    }
  }

  std::atomic<bool> busy_{false};
  std::mutex mu_;
  std::condition_variable start_, done_;
  std::vector<std::thread> workers_;
  const std::function<void()>* job_ = nullptr;
  int active_ = 0;
  int pending_ = 0;
  std::uint64_t generation_ = 0;
  std::exception_ptr error_;
  bool stop_ = false;
};

Pool& pool() {
  static Pool p;
  return p;
}

}  // namespace

int run_parallel(int threads, const std::function<void()>& participant) {
  return pool().run(threads, participant);
}

ChunkSchedule make_chunk_schedule(const std::vector<Index>& chunk_start,
                                  const std::vector<Index>& resources, Index num_resources) {
  INCISE_CHECK(!chunk_start.empty() && chunk_start.front() == 0 &&
                   chunk_start.back() == static_cast<Index>(resources.size()) &&
                   std::is_sorted(chunk_start.begin(), chunk_start.end()),
               "make_chunk_schedule: chunk_start is not a CSR offset array of resources");
  INCISE_CHECK(num_resources >= 0, "make_chunk_schedule: negative num_resources");
  for (const Index r : resources)
    INCISE_CHECK(r >= 0 && r < num_resources, "make_chunk_schedule: resource out of range");
  const int nc = static_cast<int>(chunk_start.size()) - 1;
  const auto nr = static_cast<std::size_t>(num_resources);
  // Resource → chunks touching it (CSR, each chunk once per resource, in chunk order).
  std::vector<Index> last(nr, -1);
  std::vector<Index> rstart(nr + 1, 0);
  for (int c = 0; c < nc; ++c)
    for (Index t = chunk_start[static_cast<std::size_t>(c)]; t < chunk_start[c + 1UL]; ++t) {
      const auto r = static_cast<std::size_t>(resources[static_cast<std::size_t>(t)]);
      if (last[r] != c) last[r] = c, ++rstart[r + 1];
    }
  for (std::size_t r = 0; r < nr; ++r) rstart[r + 1] += rstart[r];
  std::vector<int> rchunks(static_cast<std::size_t>(rstart[nr]));
  std::fill(last.begin(), last.end(), -1);
  {
    std::vector<Index> fill(rstart.begin(), rstart.end() - 1);
    for (int c = 0; c < nc; ++c)
      for (Index t = chunk_start[static_cast<std::size_t>(c)]; t < chunk_start[c + 1UL]; ++t) {
        const auto r = static_cast<std::size_t>(resources[static_cast<std::size_t>(t)]);
        if (last[r] != c) last[r] = c, rchunks[static_cast<std::size_t>(fill[r]++)] = c;
      }
  }
  // Neighbours of each chunk (sorted, unique).
  // A chunk meets each neighbour through many resources: `seen` keeps each once before sorting.
  std::vector<std::vector<int>> nbr(static_cast<std::size_t>(nc));
  std::vector<int> seen(static_cast<std::size_t>(nc), -1);
  for (int c = 0; c < nc; ++c) {
    std::vector<int>& n = nbr[static_cast<std::size_t>(c)];
    for (Index t = chunk_start[static_cast<std::size_t>(c)]; t < chunk_start[c + 1UL]; ++t) {
      const auto r = static_cast<std::size_t>(resources[static_cast<std::size_t>(t)]);
      for (Index k = rstart[r]; k < rstart[r + 1]; ++k) {
        const int o = rchunks[static_cast<std::size_t>(k)];
        if (o != c && seen[static_cast<std::size_t>(o)] != c) {
          seen[static_cast<std::size_t>(o)] = c;
          n.push_back(o);
        }
      }
    }
    std::sort(n.begin(), n.end());
  }
  ChunkSchedule s;
  s.colour.assign(static_cast<std::size_t>(nc), -1);
  std::vector<char> used;
  for (int c = 0; c < nc; ++c) {  // greedy: the smallest colour no earlier neighbour has
    used.assign(static_cast<std::size_t>(s.num_colours) + 1, 0);
    for (const int o : nbr[static_cast<std::size_t>(c)])
      if (o < c) used[static_cast<std::size_t>(s.colour[static_cast<std::size_t>(o)])] = 1;
    int k = 0;
    while (used[static_cast<std::size_t>(k)]) ++k;
    s.colour[static_cast<std::size_t>(c)] = k;
    s.num_colours = std::max(s.num_colours, k + 1);
  }
  s.order.resize(static_cast<std::size_t>(nc));
  for (int c = 0; c < nc; ++c) s.order[static_cast<std::size_t>(c)] = c;
  std::stable_sort(s.order.begin(), s.order.end(), [&](int a, int b) {
    return s.colour[static_cast<std::size_t>(a)] < s.colour[static_cast<std::size_t>(b)];
  });
  s.pred_start.assign(static_cast<std::size_t>(nc) + 1, 0);
  for (int c = 0; c < nc; ++c) {
    for (const int o : nbr[static_cast<std::size_t>(c)])
      if (s.colour[static_cast<std::size_t>(o)] < s.colour[static_cast<std::size_t>(c)])
        s.preds.push_back(o);
    s.pred_start[static_cast<std::size_t>(c) + 1] = static_cast<int>(s.preds.size());
  }
  return s;
}

void run_chunks(const ChunkSchedule& schedule, int threads, const std::function<void(int)>& fn) {
  const int nc = schedule.num_chunks();
  if (threads <= 1 || nc <= 1 || schedule.num_colours == nc) {
    // One thread, or nothing to overlap: the claiming order already respects every conflict.
    for (const int c : schedule.order) fn(c);
    return;
  }
  std::unique_ptr<std::atomic<bool>[]> done(new std::atomic<bool>[static_cast<std::size_t>(nc)]);
  for (int c = 0; c < nc; ++c) done[static_cast<std::size_t>(c)].store(false);
  std::atomic<int> next{0};
  run_parallel(std::min(threads, nc), [&] {
    for (;;) {
      const int k = next.fetch_add(1);
      if (k >= nc) return;
      const int c = schedule.order[static_cast<std::size_t>(k)];
      for (int p = schedule.pred_start[static_cast<std::size_t>(c)];
           p < schedule.pred_start[static_cast<std::size_t>(c) + 1]; ++p)
        while (!done[static_cast<std::size_t>(schedule.preds[static_cast<std::size_t>(p)])].load(
            std::memory_order_acquire))
          std::this_thread::yield();
      fn(c);
      done[static_cast<std::size_t>(c)].store(true, std::memory_order_release);
    }
  });
}

}  // namespace incise
