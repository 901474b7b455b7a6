#include "vtkOrthofrontPathSurface.h"

#include "vtkObjectFactory.h"

vtkStandardNewMacro(vtkOrthofrontPathSurface);
