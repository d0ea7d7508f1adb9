// jemalloc's options for the programs linked with it (server/CMakeLists.txt,
// dsoc_link_allocator): jemalloc reads this symbol when it starts.
//
// background_thread:true - pages freed for dirty_decay_ms (jemalloc's default, 10 s) are
// given back to the system by jemalloc's own threads, not on the path of whichever
// thread frees or allocates next: the tick never waits for the purge.
extern "C" {
// NOLINTNEXTLINE(cppcoreguidelines-avoid-non-const-global-variables): jemalloc's API
extern const char* malloc_conf;
const char* malloc_conf = "background_thread:true";
}
