// Build threads: the task system every parallel build runs on (oneTBB, the scheduler Embree
// itself builds with, so both share one pool of worker threads in a process), and the few
// forms of parallelism the builders use.
//
// A build's parallelism is `BuildThreads`: one thread runs the builder's own serial code and
// touches no task at all; more run it inside a tbb::task_arena limited to that many threads.
// Every builder decomposes its work the same way whatever the thread count (blocks of a fixed
// size, subtrees handed out above a fixed size), and combines the parts in a fixed order, so
// the tree does not depend on the thread count or on which thread ran what.
//
// Why results can be combined in a fixed order and still equal the serial ones: the parts
// are integer counts and box unions. A box union keeps, per coordinate, the first of equal
// minima (`a < b ? a : b` keeps b on a tie, the earlier value), so a union over blocks
// merged left to right keeps the same value — sign of a zero included — as one pass from
// left to right. (NaN would break that, but no box or centroid of a finite scene holds one.)
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>

#include "accelbench/base/default_init.h"

namespace accelbench {

// The `threads` parameter of a structure: 0 means every hardware thread.
int build_thread_count(int64_t threads_param);

class BuildThreads {
public:
    explicit BuildThreads(int threads = 1);

    int threads() const { return threads_; }
    bool parallel() const { return threads_ > 1; }

    // Runs f() on the build's threads: directly with one thread, else inside the arena
    // (f's own parallel loops and tasks then use at most threads() threads).
    template <class F>
    void run(F&& f) const {
        if (!arena_) f();
        else arena_->execute(std::forward<F>(f));
    }

private:
    int threads_;
    std::unique_ptr<tbb::task_arena> arena_;  // threads_ > 1 only
};

// Calls f(block, begin, end) for the blocks [k * block_size, min(n, (k + 1) * block_size))
// of [0, n): in parallel when `parallel`, in order otherwise. The blocks depend on n and
// block_size alone.
template <class F>
void for_blocks(bool parallel, size_t n, size_t block_size, F&& f) {
    const size_t blocks = (n + block_size - 1) / block_size;
    auto one = [&](size_t k) { f(k, k * block_size, std::min(n, (k + 1) * block_size)); };
    if (!parallel || blocks <= 1) {
        for (size_t k = 0; k < blocks; ++k) one(k);
        return;
    }
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, blocks, 1),
        [&](const tbb::blocked_range<size_t>& r) {
            for (size_t k = r.begin(); k != r.end(); ++k) one(k);
        },
        tbb::simple_partitioner());
}

inline size_t block_count(size_t n, size_t block_size) { return (n + block_size - 1) / block_size; }

// Runs a() and b(), at the same time when `parallel`.
template <class A, class B>
void fork_join(bool parallel, A&& a, B&& b) {
    if (parallel) {
        tbb::parallel_invoke(std::forward<A>(a), std::forward<B>(b));
    } else {
        a();
        b();
    }
}

// Runs f() so that a thread waiting inside it for its own parallel loops runs only tasks
// of those loops, not another subtree's: for code that keeps per-thread scratch across a
// parallel loop (tbb::this_task_arena::isolate).
template <class F>
void isolated(bool parallel, F&& f) {
    if (parallel) tbb::this_task_arena::isolate(std::forward<F>(f));
    else f();
}

}  // namespace accelbench
