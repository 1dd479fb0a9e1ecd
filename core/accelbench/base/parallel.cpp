#include "accelbench/base/parallel.h"

#include <algorithm>
#include <thread>

#include <tbb/info.h>

namespace accelbench {

int build_thread_count(int64_t threads_param) {
    if (threads_param > 0) return int(threads_param);
    return int(std::max(1u, std::thread::hardware_concurrency()));
}

BuildThreads::BuildThreads(int threads) : threads_(std::max(1, threads)) {
    // More threads than the machine has run the same parallel code on the threads there are
    // (the tree is the same; TBB would only warn that it cannot start more workers).
    if (threads_ > 1) arena_ = std::make_unique<tbb::task_arena>(std::min(threads_, tbb::info::default_concurrency()));
}

}  // namespace accelbench
