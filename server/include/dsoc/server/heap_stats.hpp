#pragma once
// What the process's C allocator says about its memory: the two figures that tell a
// server holding data (live allocations) from an allocator holding memory the server
// freed. Reads whichever allocator the process runs on:
// - jemalloc (dsoc-server links it where the build found it, server/CMakeLists.txt; or
//   preloaded): mallctl(), a few counters merged under a short lock: cheap.
// - glibc's malloc: mallinfo2(), which walks every free chunk of every arena under that
//   arena's lock: tens of milliseconds on a heap fragmented into a few hundred thousand
//   free chunks, while every allocating thread waits. A diagnosis, not a default.

#include <optional>
#include <string_view>

namespace dsoc::server {

enum class HeapAllocator { jemalloc, glibc, unknown };

[[nodiscard]] std::string_view allocator_name(HeapAllocator allocator);

/// The allocator this process runs on: jemalloc when its mallctl() is among the loaded
/// symbols, else glibc's when the program was built against glibc, else unknown.
[[nodiscard]] HeapAllocator running_heap_allocator();

/// Whether reading `allocator`'s figures makes the allocating threads wait (see above).
[[nodiscard]] constexpr bool heap_reading_is_costly(HeapAllocator allocator) {
    return allocator != HeapAllocator::jemalloc;
}

struct HeapSample {
    double in_use_bytes = 0.0; ///< live allocations [bytes]
    /// Memory the allocator holds beyond the live allocations: glibc's free chunks
    /// (resident unless trimmed), or jemalloc's resident pages less the live bytes (pages
    /// freed and not yet given back to the system, fragmentation, its own metadata).
    /// [bytes]
    double free_bytes = 0.0;
};

/// The running allocator's figures; nothing when it is unknown, or when reading it is
/// costly and `costly_allowed` is false. Thread-safe.
[[nodiscard]] std::optional<HeapSample> read_heap_sample(bool costly_allowed);

} // namespace dsoc::server
