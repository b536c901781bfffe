// What the controller build supplies instead of an operating system.
#include <chrono>

// Ruckig::update measures its own calculation duration with steady_clock; the controller has
// no OS clock to read (the firmware measures with SysTick), so this reports time zero and the
// reported calculation_duration is 0.
std::chrono::steady_clock::time_point std::chrono::steady_clock::now() noexcept {
    return time_point{};
}

// No heap on the controller. With compile-time degrees of freedom Ruckig's only std::vectors
// (waypoints, per-section limits) stay empty and never allocate; copying an empty vector does
// not call operator new. Should anything ask for memory, the firmware stops with a message
// (prf_ruckig_no_heap, a Rust panic) instead of corrupting RAM.
#include <cstddef>
#include <new>

extern "C" [[noreturn]] void prf_ruckig_no_heap();

void* operator new(std::size_t) { prf_ruckig_no_heap(); }
void operator delete(void* p, std::size_t) noexcept {
    if (p != nullptr) prf_ruckig_no_heap();
}
void operator delete(void* p) noexcept {
    if (p != nullptr) prf_ruckig_no_heap();
}
namespace std {
void __throw_bad_array_new_length() { prf_ruckig_no_heap(); }
}  // namespace std
