#include "experiments/io/vtk_output.hpp"

#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkTypeInt64Array.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {

namespace {

// The clump arrays of the design note, added to `poly`.
void add_body_arrays(vtkPolyData* poly, const sim::Particles& p, const sim::Bodies& bodies) {
  const vtkIdType n = static_cast<vtkIdType>(p.size());
  vtkNew<vtkTypeInt64Array> body_id;
  vtkNew<vtkIntArray> component;
  vtkNew<vtkDoubleArray> orientation;
  body_id->SetName("body_id");
  component->SetName("component");
  orientation->SetName("orientation");
  orientation->SetNumberOfComponents(4);
  body_id->SetNumberOfTuples(n);
  component->SetNumberOfTuples(n);
  orientation->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i) {
    const std::int32_t b = p.body[static_cast<std::size_t>(i)];
    double q[4] = {1.0, 0.0, 0.0, 0.0};
    if (b >= 0) {
      const sim::Quat& o = bodies.q[static_cast<std::size_t>(b)];
      q[0] = o.w();
      q[1] = o.x();
      q[2] = o.y();
      q[3] = o.z();
    }
    body_id->SetValue(i, b >= 0 ? bodies.id[static_cast<std::size_t>(b)] : -1);
    component->SetValue(i, p.component[static_cast<std::size_t>(i)]);
    orientation->SetTuple(i, q);
  }
  poly->GetPointData()->AddArray(body_id);
  poly->GetPointData()->AddArray(component);
  poly->GetPointData()->AddArray(orientation);
}

}  // namespace

void write_vtp(const std::string& path, const sim::Particles& p, const sim::Bodies* bodies) {
  const vtkIdType n = static_cast<vtkIdType>(p.size());
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  vtkNew<vtkCellArray> verts;
  vtkNew<vtkDoubleArray> radius, velocity, omega;
  vtkNew<vtkIntArray> material;
  vtkNew<vtkTypeInt64Array> id;
  radius->SetName("radius");
  velocity->SetName("velocity");
  velocity->SetNumberOfComponents(3);
  omega->SetName("angular_velocity");
  omega->SetNumberOfComponents(3);
  material->SetName("material");
  id->SetName("id");
  radius->SetNumberOfTuples(n);
  velocity->SetNumberOfTuples(n);
  omega->SetNumberOfTuples(n);
  material->SetNumberOfTuples(n);
  id->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i) {
    points->SetPoint(i, p.x[i].data());
    verts->InsertNextCell(1, &i);
    radius->SetValue(i, p.radius[i]);
    velocity->SetTuple(i, p.v[i].data());
    omega->SetTuple(i, p.w[i].data());
    material->SetValue(i, p.material[i]);
    id->SetValue(i, p.id[i]);
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  poly->SetVerts(verts);
  poly->GetPointData()->AddArray(radius);
  poly->GetPointData()->AddArray(velocity);
  poly->GetPointData()->AddArray(omega);
  poly->GetPointData()->AddArray(material);
  poly->GetPointData()->AddArray(id);
  if (bodies && bodies->size() > 0) add_body_arrays(poly, p, *bodies);
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  const std::string tmp = path + ".tmp.vtp";
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetFileName(tmp.c_str());
  writer->SetInputData(poly);
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  if (writer->Write() != 1) throw std::runtime_error(path + ": VTK could not write the snapshot");
  std::filesystem::rename(tmp, path);
}

SnapshotParticles read_vtp(const std::string& path) {
  if (!std::filesystem::exists(path)) throw std::runtime_error(path + ": snapshot does not exist");
  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkPolyData* poly = reader->GetOutput();
  if (!poly || !poly->GetPoints()) throw std::runtime_error(path + ": not a particle snapshot");
  auto* radius = vtkDoubleArray::SafeDownCast(poly->GetPointData()->GetArray("radius"));
  auto* material = vtkIntArray::SafeDownCast(poly->GetPointData()->GetArray("material"));
  // (The reader may give the 64-bit ids as any integer array type; ids are exact in a double.)
  vtkDataArray* body = poly->GetPointData()->GetArray("body_id");
  if (!radius) throw std::runtime_error(path + ": snapshot has no \"radius\" point data");
  SnapshotParticles s;
  const vtkIdType n = poly->GetNumberOfPoints();
  for (vtkIdType i = 0; i < n; ++i) {
    double x[3];
    poly->GetPoint(i, x);
    s.x.emplace_back(x[0], x[1], x[2]);
    s.radius.push_back(radius->GetValue(i));
    s.material.push_back(material ? material->GetValue(i) : 0);
    if (body) s.body.push_back(static_cast<std::int64_t>(body->GetComponent(i, 0)));
  }
  return s;
}

void PvdSeries::add(double time, const std::string& relative_file) {
  entries_.emplace_back(time, relative_file);
  write();
}

void PvdSeries::truncate_after(double time) {
  while (!entries_.empty() && entries_.back().first > time) entries_.pop_back();
  write();
}

void PvdSeries::load() {
  entries_.clear();
  std::ifstream in(path_);
  if (!in) return;
  const std::regex re(R"re(timestep="([^"]+)"[^>]*file="([^"]+)")re");
  std::string line;
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_search(line, m, re)) entries_.emplace_back(std::stod(m[1]), m[2]);
  }
}

void PvdSeries::write() const {
  std::ostringstream os;
  os << "<?xml version=\"1.0\"?>\n"
     << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
     << "  <Collection>\n";
  for (const auto& [t, f] : entries_)
    os << "    <DataSet timestep=\"" << std::setprecision(10) << t << "\" part=\"0\" file=\"" << f
       << "\"/>\n";
  os << "  </Collection>\n</VTKFile>\n";
  write_file_atomic(path_, os.str());
}

}  // namespace reposetwin::experiments
