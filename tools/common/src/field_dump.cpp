// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: --dump-fields writer (one .npy per field and sensor, plus index.json).
#include "tacse3/tools/field_dump.hpp"

#include <cstdio>
#include <system_error>

namespace tacse3::tools {
namespace {

constexpr float kQ16 = 1.0f / 65536.0f;
constexpr float kWorkToSensorPx = static_cast<float>(dsp::kWorkScale);

struct FieldDef {
  const char* name;
  const char* descr;  // npy dtype
  std::size_t item;
  int channels;  // 0 = scalar (N, 30, 40)
  const char* meaning;
};

const FieldDef kFields[] = {
    {"flow", "<f4", 4, 2, "raw block flow w vs the reference, sensor pixels (x, y)"},
    {"flow_valid", "|u1", 1, 0, "1 where the block flow tracked"},
    {"displacement", "<f4", 4, 2,
     "Gaussian-smoothed displacement field (input of the NHHD), sensor pixels (x, y)"},
    {"valid", "|u1", 1, 0, "1 where the smoothed field is valid"},
    {"density", "<f4", 4, 0, "Gaussian density G (dimensionless; < 0 = local expansion)"},
    {"d", "<f4", 4, 2, "NHHD curl-free part, sensor pixels"},
    {"r", "<f4", 4, 2, "NHHD divergence-free part, sensor pixels"},
    {"k", "<f4", 4, 2, "NHHD harmonic part, sensor pixels"},
    {"force", "<f4", 4, 3,
     "calibrated f^x, f^y (shear units: working pixels x shear gains) and f^z (dimensionless)"},
    {"fz_filtered", "<f4", 4, 0, "3x3-filtered f^z that the contact threshold tau is applied to"},
    {"mask", "|u1", 1, 0, "contact mask Omega (1 = contact)"},
    {"points", "<f4", 4, 3, "3D contact points q in the sensor frame, metres (0 outside Omega)"},
};

}  // namespace

std::vector<std::string> FieldDumper::field_names() {
  std::vector<std::string> n;
  for (const auto& f : kFields) n.emplace_back(f.name);
  return n;
}

std::string FieldDumper::open(const std::filesystem::path& dir, std::int64_t frames,
                              const std::array<bool, 2>& sensors, double pixel_pitch_mm) {
  dir_ = dir;
  sensors_ = sensors;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    return dir.string() + ": cannot create the --dump-fields directory";
  }
  if (std::string e = t_ns_.open(dir / "t_ns.npy", "<i8", 8, frames, {}); !e.empty()) return e;
  const char* names[2] = {"left", "right"};
  for (std::size_t k = 0; k < 2; ++k) {
    if (!sensors[k]) continue;
    std::filesystem::create_directories(dir / names[k], ec);
    if (ec) return (dir / names[k]).string() + ": cannot create directory";
    for (const auto& f : kFields) {
      auto w = std::make_unique<NpyWriter>();
      std::vector<std::int64_t> tail{dsp::kGridHeight, dsp::kGridWidth};
      if (f.channels > 0) tail.push_back(f.channels);
      if (std::string e = w->open(dir / names[k] / (std::string(f.name) + ".npy"), f.descr, f.item,
                                  frames, tail);
          !e.empty()) {
        return e;
      }
      files_[k].push_back(std::move(w));
    }
  }
  scratch_.resize(static_cast<std::size_t>(dsp::kGridCount) * 3);
  scratch_u8_.resize(static_cast<std::size_t>(dsp::kGridCount));

  // index.json: what each file holds.
  std::FILE* idx = std::fopen((dir / "index.json").c_str(), "w");
  if (idx == nullptr) return (dir / "index.json").string() + ": cannot open for writing";
  std::fprintf(idx,
               "{\n  \"format\": \"tacse3-fields\",\n  \"version\": 1,\n  \"frames\": %lld,\n"
               "  \"grid\": {\"width\": %d, \"height\": %d, \"stride_sensor_px\": %d, "
               "\"x0_sensor_px\": 3.5, \"y0_sensor_px\": 3.5},\n"
               "  \"pixel_pitch_mm\": %.9g,\n  \"t_ns\": \"t_ns.npy\",\n  \"sensors\": [",
               static_cast<long long>(frames), dsp::kGridWidth, dsp::kGridHeight,
               dsp::kGridStride * dsp::kWorkScale, pixel_pitch_mm);
  bool first = true;
  for (std::size_t k = 0; k < 2; ++k) {
    if (!sensors[k]) continue;
    std::fprintf(idx, "%s\"%s\"", first ? "" : ", ", names[k]);
    first = false;
  }
  std::fprintf(idx, "],\n  \"fields\": {\n");
  const std::size_t nf = sizeof(kFields) / sizeof(kFields[0]);
  for (std::size_t i = 0; i < nf; ++i) {
    const auto& f = kFields[i];
    std::fprintf(idx,
                 "    \"%s\": {\"file\": \"<sensor>/%s.npy\", \"dtype\": \"%s\", \"shape\": "
                 "[%lld, %d, %d%s], \"meaning\": \"%s\"}%s\n",
                 f.name, f.name, f.descr, static_cast<long long>(frames), dsp::kGridHeight,
                 dsp::kGridWidth, f.channels == 2 ? ", 2" : (f.channels == 3 ? ", 3" : ""),
                 f.meaning, i + 1 < nf ? "," : "");
  }
  std::fprintf(idx, "  }\n}\n");
  if (std::fclose(idx) != 0) return (dir / "index.json").string() + ": write error";
  return {};
}

std::string FieldDumper::append(std::int64_t t_ns,
                                const std::array<const dsp::SensorFields*, 2>& fields) {
  if (std::string e = t_ns_.append(&t_ns); !e.empty()) return e;
  const std::size_t n = static_cast<std::size_t>(dsp::kGridCount);
  for (std::size_t k = 0; k < 2; ++k) {
    if (!sensors_[k]) continue;
    const dsp::SensorFields* f = fields[k];
    auto& files = files_[k];
    std::size_t fi = 0;
    auto put_vec = [&](const dsp::VectorField* v, float scale) {
      for (std::size_t i = 0; i < n; ++i) {
        scratch_[2 * i] = v ? static_cast<float>(v->x.v[i]) * kQ16 * scale : 0.0f;
        scratch_[2 * i + 1] = v ? static_cast<float>(v->y.v[i]) * kQ16 * scale : 0.0f;
      }
      return files[fi++]->append(scratch_.data());
    };
    auto put_scalar = [&](const dsp::ScalarField* s) {
      for (std::size_t i = 0; i < n; ++i) {
        scratch_[i] = s ? static_cast<float>(s->v[i]) * kQ16 : 0.0f;
      }
      return files[fi++]->append(scratch_.data());
    };
    auto put_mask = [&](const dsp::GridMask* m) {
      for (std::size_t i = 0; i < n; ++i) scratch_u8_[i] = m ? m->v[i] : 0;
      return files[fi++]->append(scratch_u8_.data());
    };
    std::string e;
    if (e = put_vec(f ? &f->flow : nullptr, kWorkToSensorPx); !e.empty()) return e;
    if (e = put_mask(f ? &f->flow_valid : nullptr); !e.empty()) return e;
    if (e = put_vec(f ? &f->smoothed : nullptr, kWorkToSensorPx); !e.empty()) return e;
    if (e = put_mask(f ? &f->smoothed_valid : nullptr); !e.empty()) return e;
    if (e = put_scalar(f ? &f->density : nullptr); !e.empty()) return e;
    if (e = put_vec(f ? &f->d : nullptr, kWorkToSensorPx); !e.empty()) return e;
    if (e = put_vec(f ? &f->r : nullptr, kWorkToSensorPx); !e.empty()) return e;
    if (e = put_vec(f ? &f->k : nullptr, kWorkToSensorPx); !e.empty()) return e;
    for (std::size_t i = 0; i < n; ++i) {
      scratch_[3 * i] = f ? static_cast<float>(f->shear.x.v[i]) * kQ16 : 0.0f;
      scratch_[3 * i + 1] = f ? static_cast<float>(f->shear.y.v[i]) * kQ16 : 0.0f;
      scratch_[3 * i + 2] = f ? static_cast<float>(f->fz.v[i]) * kQ16 : 0.0f;
    }
    if (e = files[fi++]->append(scratch_.data()); !e.empty()) return e;
    if (e = put_scalar(f ? &f->contact.fz_filtered : nullptr); !e.empty()) return e;
    if (e = put_mask(f ? &f->contact.mask : nullptr); !e.empty()) return e;
    for (std::size_t i = 0; i < n; ++i) {
      const bool in = f && f->contact.mask.v[i] != 0;
      scratch_[3 * i] = in ? static_cast<float>(f->contact.x_nm.v[i]) * 1e-9f : 0.0f;
      scratch_[3 * i + 1] = in ? static_cast<float>(f->contact.y_nm.v[i]) * 1e-9f : 0.0f;
      scratch_[3 * i + 2] = in ? static_cast<float>(f->contact.z_nm.v[i]) * 1e-9f : 0.0f;
    }
    if (e = files[fi++]->append(scratch_.data()); !e.empty()) return e;
  }
  return {};
}

std::string FieldDumper::close() {
  if (std::string e = t_ns_.close(); !e.empty()) return e;
  for (auto& files : files_) {
    for (auto& w : files) {
      if (std::string e = w->close(); !e.empty()) return e;
    }
  }
  return {};
}

}  // namespace tacse3::tools
