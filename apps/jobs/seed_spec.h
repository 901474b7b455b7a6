#pragma once
/// Seed specifications of the command line:
///   line:x0,y0,z0:x1,y1,z1
///   circle:cx,cy,cz:nx,ny,nz:r[:open]        (closed unless :open)
///   arc:cx,cy,cz:nx,ny,nz:r:a0,a1            (degrees, open)
///   file:PATH.csv[:closed]                   (one point "x,y,z" per line, open unless :closed)
#include <string>

#include "orthofront/seed/seed_curve.h"

namespace orthofront::jobs {

/// Throws InvalidArgument naming the malformed part (or io::IoError for an unreadable file).
SeedCurve parse_seed(const std::string& spec);

}  // namespace orthofront::jobs
