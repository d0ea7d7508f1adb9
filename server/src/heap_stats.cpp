#include "dsoc/server/heap_stats.hpp"

#include <dlfcn.h>
#include <malloc.h>

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace dsoc::server {

namespace {

/// jemalloc's mallctl(name, oldp, oldlenp, newp, newlen): 0 on success.
using Mallctl = int (*)(const char*, void*, std::size_t*, void*, std::size_t);

/// mallctl() when jemalloc is loaded (linked or preloaded), else null. Looked up once.
Mallctl find_mallctl() {
    static const Mallctl found = [] {
        void* symbol = ::dlsym(RTLD_DEFAULT, "mallctl");
        Mallctl fn = nullptr;
        static_assert(sizeof fn == sizeof symbol);
        std::memcpy(&fn, &symbol, sizeof fn); // POSIX: a function's address as a void*
        return fn;
    }();
    return found;
}

std::optional<HeapSample> read_jemalloc(Mallctl mallctl) {
    // The statistics are a snapshot taken when the epoch advances.
    std::uint64_t epoch = 1;
    std::size_t epoch_size = sizeof epoch;
    if (mallctl("epoch", &epoch, &epoch_size, &epoch, sizeof epoch) != 0) {
        return std::nullopt;
    }
    std::size_t allocated = 0;
    std::size_t resident = 0;
    std::size_t size = sizeof allocated;
    if (mallctl("stats.allocated", &allocated, &size, nullptr, 0) != 0 ||
        mallctl("stats.resident", &resident, &size, nullptr, 0) != 0) {
        return std::nullopt; // a jemalloc built without statistics
    }
    HeapSample s;
    s.in_use_bytes = static_cast<double>(allocated);
    s.free_bytes = resident > allocated ? static_cast<double>(resident - allocated) : 0.0;
    return s;
}

} // namespace

std::string_view allocator_name(HeapAllocator allocator) {
    switch (allocator) {
    case HeapAllocator::jemalloc:
        return "jemalloc";
    case HeapAllocator::glibc:
        return "glibc";
    case HeapAllocator::unknown:
        break;
    }
    return "unknown";
}

HeapAllocator running_heap_allocator() {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    // AddressSanitizer and ThreadSanitizer bring their own allocator, behind glibc's
    // names: mallinfo2() answers zeros there, which are no figures at all.
    return HeapAllocator::unknown;
#else
    if (find_mallctl() != nullptr) {
        return HeapAllocator::jemalloc;
    }
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
    return HeapAllocator::glibc;
#else
    return HeapAllocator::unknown; // or a glibc without mallinfo2()
#endif
#endif
}

std::optional<HeapSample> read_heap_sample(bool costly_allowed) {
    const HeapAllocator allocator = running_heap_allocator();
    if (heap_reading_is_costly(allocator) && !costly_allowed) {
        return std::nullopt;
    }
    if (allocator == HeapAllocator::jemalloc) {
        return read_jemalloc(find_mallctl());
    }
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
    if (allocator == HeapAllocator::glibc) {
        const struct mallinfo2 info = ::mallinfo2();
        HeapSample s;
        s.in_use_bytes = static_cast<double>(info.uordblks + info.hblkhd);
        s.free_bytes = static_cast<double>(info.fordblks);
        return s;
    }
#endif
    return std::nullopt;
}

} // namespace dsoc::server
