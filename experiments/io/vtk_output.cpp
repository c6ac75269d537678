#include "experiments/io/vtk_output.hpp"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkTypeInt64Array.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <optional>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "experiments/io/numbers.hpp"
#include "experiments/io/provenance.hpp"
#include "sim/world.hpp"

namespace reposetwin::experiments {

namespace {

// One per-particle point array: its VTK name, components and how to read particle i.
struct PointArray {
  const char* name;
  int components;
  void (*get)(const sim::Particles& p, std::size_t i, double* out);
};

// The particle snapshot's point arrays. Integer arrays are written as integers below.
constexpr PointArray kPointArrays[] = {
    {"radius", 1, [](const sim::Particles& p, std::size_t i, double* o) { o[0] = p.radius[i]; }},
    {"diameter", 1,
     [](const sim::Particles& p, std::size_t i, double* o) { o[0] = 2.0 * p.radius[i]; }},
    {"velocity", 3,
     [](const sim::Particles& p, std::size_t i, double* o) {
       for (int k = 0; k < 3; ++k) o[k] = p.v[i][k];
     }},
    {"angular_velocity", 3,
     [](const sim::Particles& p, std::size_t i, double* o) {
       for (int k = 0; k < 3; ++k) o[k] = p.w[i][k];
     }},
};

// VTK's file writer does not report a short write (a full disk leaves a truncated file and
// Write() == 1), so the XML is made in memory and published by write_file_atomic, which checks
// every write, syncs and renames: a reader sees the old file or the whole new one.
void write_poly(const std::string& path, vtkPolyData* poly, const char* what) {
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->WriteToOutputStringOn();
  writer->SetInputData(poly);
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  if (writer->Write() != 1)
    throw std::runtime_error(path + ": VTK could not write the " + std::string(what));
  write_file_atomic(path, writer->GetOutputString());
}

void add_field(vtkFieldData* fd, const char* name, std::initializer_list<double> values) {
  vtkNew<vtkDoubleArray> a;
  a->SetName(name);
  for (const double v : values) a->InsertNextValue(v);
  fd->AddArray(a);
}

void add_field(vtkFieldData* fd, const char* name, const std::vector<std::string>& values) {
  vtkNew<vtkStringArray> a;
  a->SetName(name);
  for (const std::string& v : values) a->InsertNextValue(v);
  fd->AddArray(a);
}

void write_frame_info(vtkFieldData* fd, const FrameInfo& info) {
  add_field(fd, "time_s", {info.time_s});
  add_field(fd, "phase", std::vector<std::string>{info.phase});
  add_field(fd, "settled", {info.settled ? 1.0 : 0.0});
  add_field(fd, "plate", {info.plate_half_size_m, info.plate_thickness_m});
  if (info.container) {
    const ShellPlacement& c = *info.container;
    add_field(fd, "container", {c.z_bottom_m, c.z_top_m, c.r_bottom_m, c.r_top_m});
  }
  add_field(fd, "material_names", info.material_names);
  if (!info.scene_fnv1a.empty())
    add_field(fd, "scene_fnv1a", std::vector<std::string>{info.scene_fnv1a});
}

std::optional<FrameInfo> read_frame_info(vtkFieldData* fd) {
  auto* time = fd ? vtkDoubleArray::SafeDownCast(fd->GetAbstractArray("time_s")) : nullptr;
  if (!time) return std::nullopt;
  FrameInfo info;
  info.time_s = time->GetValue(0);
  if (auto* phase = vtkStringArray::SafeDownCast(fd->GetAbstractArray("phase")))
    info.phase = phase->GetValue(0);
  if (auto* settled = vtkDoubleArray::SafeDownCast(fd->GetAbstractArray("settled")))
    info.settled = settled->GetValue(0) != 0.0;
  if (auto* plate = vtkDoubleArray::SafeDownCast(fd->GetAbstractArray("plate"));
      plate && plate->GetNumberOfValues() == 2) {
    info.plate_half_size_m = plate->GetValue(0);
    info.plate_thickness_m = plate->GetValue(1);
  }
  if (auto* c = vtkDoubleArray::SafeDownCast(fd->GetAbstractArray("container"));
      c && c->GetNumberOfValues() == 4)
    info.container = ShellPlacement{c->GetValue(0), c->GetValue(1), c->GetValue(2), c->GetValue(3)};
  if (auto* names = vtkStringArray::SafeDownCast(fd->GetAbstractArray("material_names")))
    for (vtkIdType k = 0; k < names->GetNumberOfValues(); ++k)
      info.material_names.push_back(names->GetValue(k));
  if (auto* scene = vtkStringArray::SafeDownCast(fd->GetAbstractArray("scene_fnv1a"));
      scene && scene->GetNumberOfValues() == 1)
    info.scene_fnv1a = scene->GetValue(0);
  return info;
}

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

void write_vtp(const std::string& path, const sim::Particles& p, const FrameInfo& info,
               const sim::Bodies* bodies) {
  const vtkIdType n = static_cast<vtkIdType>(p.size());
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  vtkNew<vtkCellArray> verts;
  vtkNew<vtkPolyData> poly;
  for (vtkIdType i = 0; i < n; ++i) {
    points->SetPoint(i, p.x[i].data());
    verts->InsertNextCell(1, &i);
  }
  for (const PointArray& spec : kPointArrays) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(spec.name);
    a->SetNumberOfComponents(spec.components);
    a->SetNumberOfTuples(n);
    double v[3];
    for (vtkIdType i = 0; i < n; ++i) {
      spec.get(p, static_cast<std::size_t>(i), v);
      a->SetTuple(i, v);
    }
    poly->GetPointData()->AddArray(a);
  }
  vtkNew<vtkIntArray> material;
  vtkNew<vtkTypeInt64Array> id;
  material->SetName("material");
  id->SetName("id");
  material->SetNumberOfTuples(n);
  id->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i) {
    material->SetValue(i, p.material[i]);
    id->SetValue(i, p.id[i]);
  }
  poly->SetPoints(points);
  poly->SetVerts(verts);
  poly->GetPointData()->AddArray(material);
  poly->GetPointData()->AddArray(id);
  if (bodies && bodies->size() > 0) add_body_arrays(poly, p, *bodies);
  write_frame_info(poly->GetFieldData(), info);
  write_poly(path, poly, "snapshot");
}

void write_plate_vtp(const std::string& path, const FrameInfo& info) {
  const double h = info.plate_half_size_m, t = info.plate_thickness_m;
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  for (int k = 0; k < 8; ++k)  // corner k: bit 0 = +x, bit 1 = +y, bit 2 = top (z = 0)
    points->InsertNextPoint(k & 1 ? h : -h, k & 2 ? h : -h, k & 4 ? 0.0 : -t);
  // Six faces, each wound outwards.
  const vtkIdType faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                 {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  vtkNew<vtkCellArray> quads;
  for (const auto& f : faces) quads->InsertNextCell(4, f);
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  poly->SetPolys(quads);
  write_poly(path, poly, "plate");
}

void write_shell_vtp(const std::string& path, const ShellPlacement& shell, int segments) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  vtkNew<vtkCellArray> quads;
  for (int i = 0; i < segments; ++i) {
    const double a = 2.0 * std::numbers::pi * i / segments;
    points->InsertNextPoint(shell.r_bottom_m * std::cos(a), shell.r_bottom_m * std::sin(a),
                            shell.z_bottom_m);
    points->InsertNextPoint(shell.r_top_m * std::cos(a), shell.r_top_m * std::sin(a),
                            shell.z_top_m);
  }
  for (int i = 0; i < segments; ++i) {
    const vtkIdType j = (i + 1) % segments;
    const vtkIdType q[4] = {2 * i, 2 * j, 2 * j + 1, 2 * i + 1};
    quads->InsertNextCell(4, q);
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  poly->SetPolys(quads);
  write_poly(path, poly, "shell");
}

std::size_t write_contacts_vtp(const std::string& path, const sim::State& st) {
  const sim::NeighborList& nl = st.neighbors;
  const sim::Particles& p = st.particles;
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  vtkNew<vtkCellArray> lines;
  vtkNew<vtkDoubleArray> force, magnitude;
  force->SetName("force");
  force->SetNumberOfComponents(3);
  magnitude->SetName("force_magnitude");
  // The reactions are those of the last force phase, stored by incoming slot.
  const bool usable = st.forces_valid && nl.start.size() == p.size() + 1 &&
                      nl.in_slot.size() == nl.pairs() && st.reaction.size() >= nl.pairs();
  for (std::size_t i = 0; usable && i < p.size(); ++i) {
    for (std::int32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      const sim::Vec3& f = st.reaction[static_cast<std::size_t>(nl.in_slot[k])].force;
      if (f.squaredNorm() == 0.0) continue;  // not touching
      const vtkIdType a = points->InsertNextPoint(p.x[i].data());
      const vtkIdType b = points->InsertNextPoint(p.x[static_cast<std::size_t>(nl.second[k])].data());
      const vtkIdType ends[2] = {a, b};
      lines->InsertNextCell(2, ends);
      force->InsertNextTuple(f.data());
      magnitude->InsertNextValue(f.norm());
    }
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  poly->SetLines(lines);
  poly->GetCellData()->AddArray(force);
  poly->GetCellData()->AddArray(magnitude);
  write_poly(path, poly, "contacts");
  return static_cast<std::size_t>(lines->GetNumberOfCells());
}

namespace {
// A snapshot of 100 million grains is a few GB; a larger file is not one of ours.
constexpr std::uintmax_t kMaxSnapshotBytes = std::uintmax_t{16} << 30;
}  // namespace

SnapshotParticles read_vtp(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(std::filesystem::symlink_status(path, ec)))
    throw std::runtime_error(path + ": snapshot does not exist");
  // VTK opens the file itself: a FIFO or a device is refused before it does.
  check_input_file(path, kMaxSnapshotBytes);
  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName(path.c_str());
  // VTK prints a reader's errors itself, as coloured log lines with its source file and line; a
  // file that is not a snapshot is this function's message, naming the file, and nothing else.
  const bool warnings = vtkObject::GetGlobalWarningDisplay();
  vtkObject::GlobalWarningDisplayOff();
  reader->Update();
  vtkObject::SetGlobalWarningDisplay(warnings);
  vtkPolyData* poly = reader->GetOutput();
  if (reader->GetErrorCode() != 0 || !poly || !poly->GetPoints())
    throw std::runtime_error(path +
                             ": not a particle snapshot (a VTK XML PolyData file with "
                             "the points and their \"radius\" is expected)");
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
  s.info = read_frame_info(poly->GetFieldData());
  return s;
}

void PvdSeries::add(double time, const std::string& relative_file) {
  add(time, std::vector<std::string>{relative_file});
}

void PvdSeries::add(double time, const std::vector<std::string>& relative_files) {
  for (std::size_t k = 0; k < relative_files.size(); ++k)
    entries_.push_back({time, static_cast<int>(k), relative_files[k]});
  write();
}

void PvdSeries::truncate_after(double time) {
  while (!entries_.empty() && entries_.back().time > time) entries_.pop_back();
  write();
}

void PvdSeries::load() {
  entries_.clear();
  std::ifstream in(path_);
  if (!in) return;
  const std::regex re(R"re(timestep="([^"]+)"\s+part="([0-9]+)"\s+file="([^"]+)")re");
  std::string line;
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_search(line, m, re)) {
      const std::optional<double> t = parse_plain_decimal(m[1].str());
      const std::optional<std::uint64_t> part = parse_seed(m[2].str());
      if (!t || !part || *part > 1000000)
        throw std::runtime_error(path_ + ": a series entry with timestep \"" + m[1].str() +
                                 "\" and part \"" + m[2].str() + "\" is not one of ours");
      entries_.push_back({*t, static_cast<int>(*part), m[3]});
    }
  }
}

void PvdSeries::write() const {
  std::ostringstream os;
  os << "<?xml version=\"1.0\"?>\n"
     << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
     << "  <Collection>\n";
  for (const Entry& e : entries_)
    os << "    <DataSet timestep=\"" << std::setprecision(10) << e.time << "\" part=\"" << e.part
       << "\" file=\"" << e.file << "\"/>\n";
  os << "  </Collection>\n</VTKFile>\n";
  write_file_atomic(path_, os.str());
}

}  // namespace reposetwin::experiments
