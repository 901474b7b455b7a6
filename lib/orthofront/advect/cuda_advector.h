#pragma once
/// The CUDA backend of BatchAdvector (built only with ORTHOFRONT_HAVE_CUDA). This header has no
/// CUDA types: the host side sees a BatchAdvector like any other.
#include <cstddef>
#include <memory>
#include <string>

#include "orthofront/advect/batch_advector.h"

namespace orthofront::advect {

/// True when a CUDA device can be used; otherwise `why` has the runtime's reason.
bool cuda_device_present(std::string* why);

/// Bytes per second of a copy of `bytes` from pinned host memory to the device (best of three).
double cuda_pinned_upload_rate(std::size_t bytes);

/// Particles live on the device for the whole call; each step is copied once into pinned memory
/// and uploaded on its own stream while the kernels of the slab before it run (two pinned staging
/// buffers). Steps stay on the device between calls, least recently used first out, as many as
/// `device_bytes` holds (at least three; 0: half the device memory free at the first call), so a
/// front spread over many steps does not upload them again every call. Calls from different
/// threads run at once (up to 16, each on a stream of its own), sharing the resident steps.
/// Arithmetic in double on float samples, FMA contraction off so a sample and an RK4 step give
/// the CPU's bits.
std::unique_ptr<BatchAdvector> make_cuda_advector(std::size_t device_bytes = 0);

}  // namespace orthofront::advect
