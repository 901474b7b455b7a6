#include "vtkOrthofrontStreamSurface.h"

#include "vtkObjectFactory.h"

vtkStandardNewMacro(vtkOrthofrontStreamSurface);
