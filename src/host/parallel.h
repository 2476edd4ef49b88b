// Runs fn(0) … fn(n − 1) on up to `jobs` threads (the caller's among them). Each index runs
// once, and the results go wherever fn puts them by index, so the output does not depend on
// the thread count. An exception from fn(i) is rethrown after every thread has finished, the
// lowest index's first (what one thread would have thrown).
#pragma once
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <thread>
#include <vector>

namespace battsim {
namespace host {

template <typename Fn>
void parallel_for(std::size_t n, int jobs, Fn&& fn) {
    std::vector<std::exception_ptr> errors(n);
    std::atomic<std::size_t> next{0};
    const auto worker = [&]() {
        for (;;) {
            const std::size_t i = next.fetch_add(1);
            if (i >= n) return;
            try {
                fn(i);
            } catch (...) {
                errors[i] = std::current_exception();
            }
        }
    };
    const std::size_t wanted = std::min<std::size_t>(static_cast<std::size_t>(std::max(jobs, 1)), n);
    std::vector<std::thread> threads;
    for (std::size_t j = 1; j < wanted; ++j) threads.emplace_back(worker);
    worker();
    for (std::thread& t : threads) t.join();
    for (const std::exception_ptr& e : errors) {
        if (e) std::rethrow_exception(e);
    }
}

}  // namespace host
}  // namespace battsim
