#include "vtkOrthofrontStreakSurface.h"

#include "vtkObjectFactory.h"

vtkStandardNewMacro(vtkOrthofrontStreakSurface);
