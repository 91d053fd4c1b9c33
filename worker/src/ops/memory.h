#pragma once
// The process's resident memory (Linux /proc/self): what the work loop records per job and
// bounds with queue.job_memory_mib. Each call reads the file afresh; nullopt / false where the
// system does not answer (another OS, a restricted /proc).

#include <cstdint>
#include <optional>

namespace csgtile::worker::ops {

/// Resident set size now (VmRSS), in bytes.
std::optional<std::uint64_t> resident_bytes();
/// Highest resident set size since the process started or since reset_peak_resident (VmHWM).
std::optional<std::uint64_t> peak_resident_bytes();
/// The same in MiB, to a tenth (as timings.json records it).
std::optional<double> peak_resident_mib();
/// Starts a new peak at the current resident size (writes "5" to /proc/self/clear_refs), so
/// that the next peak_resident_bytes is one job's. Returns false where refused.
bool reset_peak_resident();

}  // namespace csgtile::worker::ops
