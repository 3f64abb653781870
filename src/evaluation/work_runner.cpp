#include "selfsense/evaluation/work_runner.hpp"

#include <exception>
#include <future>
#include <vector>

namespace selfsense::evaluation {

void run_on_threads(std::span<const std::function<void()>> work) {
  if (work.empty()) return;
  std::vector<std::future<void>> started;
  started.reserve(work.size() - 1);
  for (const auto& piece : work.subspan(1))
    started.push_back(std::async(std::launch::async, piece));
  std::exception_ptr first;
  try {
    work.front()();
  } catch (...) {
    first = std::current_exception();
  }
  // Every piece ends before this returns or throws (a future's get waits for its thread).
  for (auto& f : started) {
    try {
      f.get();
    } catch (...) {
      if (!first) first = std::current_exception();
    }
  }
  if (first) std::rethrow_exception(first);
}

}  // namespace selfsense::evaluation
