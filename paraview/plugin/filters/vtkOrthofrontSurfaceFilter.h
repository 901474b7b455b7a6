#pragma once
/// The orthofront surface filters' common part: the vector field from image data or a
/// rectilinear grid (for path and streak surfaces its time steps, asked of the pipeline one at a
/// time), the seed line, the options by name (each filter's generated setters store them), and
/// the surface as vtkPolyData with its per-vertex attributes and the run's report as field data.
/// A streak surface's output has a time step per frame.
#include <initializer_list>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "OrthofrontFiltersModule.h"
#include "vtkPolyDataAlgorithm.h"
#include "vtkSmartPointer.h"

class vtkPolyData;

class ORTHOFRONTFILTERS_EXPORT vtkOrthofrontSurfaceFilter : public vtkPolyDataAlgorithm {
 public:
  vtkTypeMacro(vtkOrthofrontSurfaceFilter, vtkPolyDataAlgorithm)
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// The seed line's ends (world units).
  vtkSetVector3Macro(Point1, double);
  vtkGetVector3Macro(Point1, double);
  vtkSetVector3Macro(Point2, double);
  vtkGetVector3Macro(Point2, double);
  /// A cell with a zero vector at a corner has no data (as when files are read); 0: zeros flow.
  vtkSetMacro(ZerosAreNoData, int);
  vtkGetMacro(ZerosAreNoData, int);
  vtkBooleanMacro(ZerosAreNoData, int);

  /// The last run's report (JSON, as `--report` writes it); also the output's field data
  /// "orthofront_report".
  const char* GetReport() const { return this->Report.c_str(); }

 protected:
  explicit vtkOrthofrontSurfaceFilter(const char* kind);
  ~vtkOrthofrontSurfaceFilter() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation* request, vtkInformationVector** inputVector,
                         vtkInformationVector* outputVector) override;
  int RequestUpdateExtent(vtkInformation* request, vtkInformationVector** inputVector,
                          vtkInformationVector* outputVector) override;
  int RequestData(vtkInformation* request, vtkInformationVector** inputVector,
                  vtkInformationVector* outputVector) override;

  // The generated setters: each stores its option's value as the option schema reads it.
  void SetOptionValue(const char* option, double value);
  void SetOptionValue(const char* option, int value);
  void SetOptionValue(const char* option, vtkIdType value);
  void SetOptionValue(const char* option, int value, bool flag);
  void SetOptionValue(const char* option, int index, std::initializer_list<const char*> words);
  void SetOptionValue(const char* option, const char* value);

  double Point1[3] = {0, 0, 0};
  double Point2[3] = {1, 0, 0};
  int ZerosAreNoData = 1;

 private:
  vtkOrthofrontSurfaceFilter(const vtkOrthofrontSurfaceFilter&) = delete;
  void operator=(const vtkOrthofrontSurfaceFilter&) = delete;
  void StoreOption(const char* option, const std::string& text);
  // Path and streak surfaces: the input times the run needs (throws InvalidArgument).
  std::vector<double> NeededTimes() const;
  // Takes one time step of the input; builds the surface once the last is in.
  void CollectStep(vtkInformation* request, vtkInformationVector** inputVector);
  void OutputFrame(vtkInformationVector* outputVector);
  void RunStream(vtkInformationVector** inputVector, vtkPolyData* output);

  std::string Kind;
  std::map<std::string, std::string> Options;
  std::string Report;
  std::vector<double> InputTimes;
  // Path and streak surfaces: the steps being collected, and the surfaces built from them (one,
  // or one a frame) with the options and input they were built from.
  struct Run;
  std::unique_ptr<Run> Collecting;
  std::vector<double> FrameTimes;
  std::vector<vtkSmartPointer<vtkPolyData>> Surfaces;
  vtkMTimeType SurfacesKey = 0;
};
