#pragma once
/// Marks functions compiled for both the host and a CUDA device. Without nvcc it is empty, so the
/// CPU build sees plain inline C++ and never needs CUDA.
#if defined(__CUDACC__)
#define ORTHOFRONT_HD __host__ __device__
#else
#define ORTHOFRONT_HD
#endif
