// The chunked mode's passes (issue 14) against the in-memory functions they
// stand for, on garments stored with tiny chunks: the same sums, welds, layers,
// agents, attachments and slices, to the bit.
#include <refit/chunked/chunked_attach.hpp>
#include <refit/chunked/chunked_features.hpp>
#include <refit/chunked/chunked_surface.hpp>
#include <refit/chunked/chunked_symmetry.hpp>
#include <refit/chunked/deterministic_sum.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/weld.hpp>
#include <refit/features/symmetry.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/surface/agents.hpp>

#include <mannequin/mannequin.hpp>
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <random>

namespace refit {
namespace {

TEST(DeterministicSum, GivesDeterministicSumsBits) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1e3, 1e3);
  for (const std::size_t n : {0, 1, 5, 2047, 2048, 2049, 10000, 123457})
    for (const std::size_t grain : {1, 7, 2048}) {
      std::vector<double> v(n);
      for (double& x : v) x = u(rng) * std::pow(10.0, double(rng() % 9) - 4.0);
      DeterministicSum s(0, n, grain);
      for (std::size_t i = 0; i < n; ++i) s.add(i, v[i]);
      const double expected = deterministic_sum(0, n, grain, 0.0, [&](std::size_t i) { return v[i]; });
      EXPECT_EQ(std::bit_cast<std::uint64_t>(s.result()), std::bit_cast<std::uint64_t>(expected)) << n << " " << grain;
    }
}

// A garment written to a file, then stored in tiny chunks.
struct Stored {
  test::TempDir dir;
  Garment g;
  std::shared_ptr<GarmentStore> store;
  ChunkPlan plan;
  Stored(const Garment& garment, std::size_t chunk, std::size_t gather_bytes) {
    write_garment_obj(dir.file("g.obj"), garment);
    g = read_garment_obj(dir.file("g.obj"));
    plan.chunk_vertices = chunk;
    plan.chunk_faces = chunk;
    plan.group_bytes = 1;
    plan.gather_bytes = gather_bytes;
    plan.folder = dir.path();
    ObjStream obj(dir.file("g.obj"), plan.group_bytes);
    store = std::make_shared<GarmentStore>(std::move(obj), plan.folder);
  }
};

std::vector<Garment> garments() {
  std::vector<Garment> out;
  mannequin::BodyParams body;
  mannequin::GarmentParams p;
  p.target_vertices = 3000;
  p.soup = true;
  out.push_back(mannequin::make_garment(body, p));
  p.soup = false;
  p.two_layers = true;
  out.push_back(mannequin::make_garment(body, p));
  const std::string data = test::shared_data_dir();
  if (!data.empty()) {
    out.push_back(read_garment_obj(data + "/garments/outfit_dress_jeans_on_A_female.obj"));
    out.push_back(read_garment_obj(data + "/garments/dress_soup_on_A_female.obj"));
  }
  return out;
}

bool same_bits(const Points& a, const Points& b) {
  return a.rows() == b.rows() && std::memcmp(a.data(), b.data(), sizeof(double) * std::size_t(a.size())) == 0;
}

TEST(ChunkedStages, WeldLayersAgentsAttachmentsAndSlicesAreTheInMemoryOnes) {
  for (const Garment& garment : garments())
    for (const std::size_t gather : {std::size_t(0), std::size_t(1) << 30}) {
      const Stored s(garment, 97, gather);
      const Garment& g = s.g;
      SCOPED_TRACE(std::to_string(g.vertex_count()) + " vertices, gather " + std::to_string(gather));
      const PointGather x(s.store->positions(), s.plan.gather_bytes);
      EXPECT_EQ(x.resident(), gather > 0);

      // Welding in chunks.
      const double tol = 1e-6 * bounding_box_diagonal(g.positions);
      PointWelder welder(g.vertex_count(), tol);
      for_each_chunk(s.store->positions(), 97, [&](std::size_t, const Points& rows) { welder.mark(rows); });
      std::vector<Index> rep;
      for_each_chunk(s.store->positions(), 97, [&](std::size_t first, const Points& rows) {
        const auto part = welder.cluster(first, rows, welder.candidates(rows));
        rep.insert(rep.end(), part.begin(), part.end());
      });
      EXPECT_EQ(rep, weld_points(g.positions, tol));

      SurfaceOptions o;
      const double h = surface_voxel(g, o);
      const auto measure = chunked_surface_measure(*s.store, x, s.plan), expected = surface_measure(g);
      EXPECT_EQ(std::bit_cast<std::uint64_t>(measure.first), std::bit_cast<std::uint64_t>(expected.first));
      EXPECT_EQ(std::bit_cast<std::uint64_t>(measure.second), std::bit_cast<std::uint64_t>(expected.second));
      EXPECT_EQ(std::bit_cast<std::uint64_t>(chunked_surface_voxel(*s.store, measure, o)), std::bit_cast<std::uint64_t>(h));
      const std::vector<std::uint32_t> layers = surface_layers(g, o, h);
      EXPECT_EQ(chunked_layers(*s.store, x, s.plan, o.layer_min_area * h * h, o.layer_join * h), layers);

      const VoxelGrid grid = make_voxel_grid(g, Points(0, 3), h);
      const GarmentAgents a = select_agents(g, grid, {}, layers);
      const GarmentAgents c = chunked_select_agents(*s.store, x, s.plan, grid, {}, layers);
      EXPECT_EQ(c.samples, a.samples);
      EXPECT_EQ(c.vertex, a.vertex);
      EXPECT_EQ(c.weight, a.weight);
      EXPECT_EQ(c.voxel, a.voxel);
      EXPECT_EQ(c.layer, a.layer);

      // Points near and off the surface.
      Points samples(40, 3);
      for (Eigen::Index k = 0; k < samples.rows(); ++k)
        samples.row(k) = g.positions.row((k * 7919) % g.positions.rows()) + Eigen::RowVector3d(0.3 * (k % 3), -0.1 * k, 0.05);
      const SurfaceAttachment m = attach_points(g, samples), ca = chunked_attach(*s.store, x, s.plan, samples);
      EXPECT_EQ(ca.vertex, m.vertex);
      EXPECT_EQ(ca.weight, m.weight);
      EXPECT_TRUE(same_bits(ca.offset, m.offset));

      const Vec3 centre = 0.5 * (g.positions.colwise().minCoeff() + g.positions.colwise().maxCoeff()).transpose();
      FeaturePlane plane;
      plane.point = centre;
      plane.normal = Vec3(0.1, 1.0, 0.2).normalized();
      const FeatureGarment fg = chunked_feature_garment(*s.store, x, s.plan);
      const SliceResult cs = fg.slice(plane, tol), ms = slice_garment(g, plane, tol);
      ASSERT_EQ(cs.pieces.size(), ms.pieces.size());
      for (std::size_t i = 0; i < cs.pieces.size(); ++i) {
        EXPECT_EQ(cs.pieces[i].closed, ms.pieces[i].closed);
        EXPECT_TRUE(same_bits(cs.pieces[i].points, ms.pieces[i].points));
      }
      EXPECT_EQ(cs.segments, ms.segments);
    }
}

// The mirror images found slab by slab, and where a slab holds more than a
// tile's elements, column by column across it: within the radius, each is
// the in-memory locator's, bit for bit.
TEST(ChunkedStages, MirrorImagesInSlabsAndColumnsAreTheInMemoryOnes) {
  for (const Garment& garment : garments())
    for (const std::size_t chunk : {std::size_t(60), std::size_t(100000)}) {
      const Stored s(garment, chunk, 0);
      const Garment& g = s.g;
      SCOPED_TRACE(std::to_string(g.vertex_count()) + " vertices, chunks of " + std::to_string(chunk));
      const PointGather x(s.store->positions(), s.plan.gather_bytes);
      // A plane off the middle: the images land at every distance from the surface up to the radius.
      const double radius = 0.1 * bounding_box_diagonal(g.positions);  // each slab holds its neighbours within it: columns
      const double c = 0.5 * (g.positions.col(0).minCoeff() + g.positions.col(0).maxCoeff()) + 0.3 * radius;
      const ChunkedMirror m = chunked_mirror_attach(*s.store, x, s.plan, c, radius);
      if (chunk < 100000) EXPECT_GT(m.columns, 0u) << "no slab was cut across";
      else EXPECT_EQ(m.columns, 0u);
      const SurfaceAttachment at = attach_points(g, mirror_x(g.positions, c));
      std::vector<MirrorRecord> rec;
      m.records.read(0, g.vertex_count(), rec);
      std::size_t within = 0;
      for (std::size_t v = 0; v < g.vertex_count(); ++v) {
        const double d = at.offset.row(Eigen::Index(v)).norm();
        if (!(d <= radius)) {
          EXPECT_FALSE(rec[v].distance() < d * (1 - 1e-12)) << "vertex " << v << ": an image closer than the locator's";
          continue;
        }
        ++within;
        ASSERT_EQ(rec[v].vertex, at.vertex[v]) << "vertex " << v;
        ASSERT_EQ(std::memcmp(rec[v].weight.data(), at.weight[v].data(), sizeof(double) * 3), 0) << "vertex " << v;
        for (int k = 0; k < 3; ++k)
          ASSERT_EQ(std::bit_cast<std::uint64_t>(rec[v].offset[std::size_t(k)]),
                    std::bit_cast<std::uint64_t>(at.offset(Eigen::Index(v), k)))
              << "vertex " << v;
      }
      EXPECT_GT(within, g.vertex_count() / 2);
    }
}

}  // namespace
}  // namespace refit
