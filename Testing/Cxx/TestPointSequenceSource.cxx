// SPDX-License-Identifier: BSD-3-Clause
// vtkPointSequenceSource in a VTK pipeline: time steps, per-frame reads, errors and warnings.
#include "TestUtilities.h"

#include "dp/io/PointCloudIO.h"

#include "vtkCommand.h"
#include "vtkFieldData.h"
#include "vtkInformation.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPointSequenceSource.h"
#include "vtkPolyData.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkStringArray.h"
#include "vtkXMLPolyDataWriter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace
{

using dp::test::TempDir;
using dp::test::writeText;

// Records ErrorEvent / WarningEvent messages instead of printing them.
class MessageLog : public vtkCommand
{
public:
  static MessageLog* New() { return new MessageLog; }
  void Execute(vtkObject*, unsigned long event, void* data) override
  {
    (event == vtkCommand::ErrorEvent ? Errors : Warnings) += static_cast<const char*>(data);
  }
  std::string Errors, Warnings;
};

dp::PointCloud cloudOf(std::size_t n, double z)
{
  dp::PointCloud c;
  for (std::size_t i = 0; i < n; ++i)
    c.points.insert(c.points.end(), {static_cast<double>(i), 0.0, z});
  return c;
}

struct Fixture
{
  TempDir dir;
  vtkNew<vtkPointSequenceSource> source;
  vtkNew<MessageLog> log;
  Fixture()
  {
    source->AddObserver(vtkCommand::ErrorEvent, log);
    source->AddObserver(vtkCommand::WarningEvent, log);
  }
  vtkPolyData* at(double t)
  {
    log->Errors.clear();
    log->Warnings.clear();
    source->UpdateTimeStep(t);
    return source->GetOutput();
  }
  std::string fileOf(vtkPolyData* pd)
  {
    auto* names = vtkStringArray::SafeDownCast(pd->GetFieldData()->GetAbstractArray("FileName"));
    return names ? names->GetValue(0) : std::string();
  }
};

TEST(PointSequenceSource, PublishesTimeStepsAndReadsEachFrameInNaturalOrder)
{
  Fixture f;
  // Frame k has k+1 points and z = k, under names that sort wrongly as plain strings.
  const char* names[] = {"s1.ply", "s2.pcd", "s3.xyz", "s10.obj", "s11.csv"};
  for (int k = 0; k < 5; ++k)
    dp::writePointCloud(f.dir.file(names[k]), cloudOf(k + 1, k));
  f.source->SetDirectoryName(f.dir.path().c_str());
  f.source->SetFrameInterval(0.5);
  ASSERT_EQ(f.source->GetNumberOfFrames(), 5);

  vtkInformation* info = f.source->GetOutputInformation(0);
  ASSERT_TRUE(info->Has(vtkStreamingDemandDrivenPipeline::TIME_STEPS()));
  EXPECT_EQ(info->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS()), 5);
  const double* range = info->Get(vtkStreamingDemandDrivenPipeline::TIME_RANGE());
  EXPECT_DOUBLE_EQ(range[0], 0.0);
  EXPECT_DOUBLE_EQ(range[1], 2.0);

  for (int k = 0; k < 5; ++k)
  {
    vtkPolyData* out = f.at(0.5 * k);
    EXPECT_EQ(f.log->Errors, "");
    EXPECT_EQ(out->GetNumberOfPoints(), k + 1) << names[k];
    EXPECT_EQ(out->GetNumberOfVerts(), k + 1);
    EXPECT_DOUBLE_EQ(out->GetPoint(0)[2], k);
    EXPECT_EQ(f.fileOf(out), f.dir.file(names[k]));
    EXPECT_DOUBLE_EQ(out->GetInformation()->Get(vtkDataObject::DATA_TIME_STEP()), 0.5 * k);
  }
  // A time between frames shows the frame before it.
  EXPECT_EQ(f.at(1.2)->GetNumberOfPoints(), 3);
}

TEST(PointSequenceSource, SeriesFileTimesAndPatternAndExplicitList)
{
  Fixture f;
  for (int k = 0; k < 3; ++k)
    dp::writePLY(f.dir.file("p" + std::to_string(k) + ".ply"), cloudOf(10 + k, 0));
  writeText(f.dir.file("seq.series"),
            R"({"file-series-version":"1.0","files":[{"name":"p0.ply","time":1.5},
               {"name":"p2.ply","time":4.0}]})");
  f.source->SetFileName(f.dir.file("seq.series").c_str());
  ASSERT_EQ(f.source->GetNumberOfFrames(), 2);
  EXPECT_DOUBLE_EQ(f.source->GetFrameTime(1), 4.0);
  EXPECT_EQ(f.at(4.0)->GetNumberOfPoints(), 12);

  f.source->AddFileName(f.dir.file("p2.ply").c_str()); // the list wins over FileName
  f.source->AddFileName(f.dir.file("p1.ply").c_str());
  ASSERT_EQ(f.source->GetNumberOfFrames(), 2);
  EXPECT_EQ(f.at(0.0)->GetNumberOfPoints(), 12);
  EXPECT_EQ(f.at(1.0)->GetNumberOfPoints(), 11);
}

TEST(PointSequenceSource, ABadFrameIsAnErrorNamingItAndTheOtherFramesStillRead)
{
  Fixture f;
  for (int k = 0; k < 4; ++k)
    dp::writePLY(f.dir.file("f" + std::to_string(k) + ".ply"), cloudOf(5, k));
  // Frame 2 truncated, frame 3 has an extension nobody reads inside a .series.
  const std::string whole = dp::test::readText(f.dir.file("f2.ply"));
  writeText(f.dir.file("f2.ply"), whole.substr(0, whole.size() - 7));
  f.source->SetDirectoryName(f.dir.path().c_str());
  ASSERT_EQ(f.source->GetNumberOfFrames(), 4);
  EXPECT_EQ(f.at(1)->GetNumberOfPoints(), 5);
  vtkPolyData* bad = f.at(2);
  EXPECT_NE(f.log->Errors.find(f.dir.file("f2.ply")), std::string::npos) << f.log->Errors;
  EXPECT_NE(f.log->Errors.find("truncated"), std::string::npos) << f.log->Errors;
  EXPECT_EQ(bad->GetNumberOfPoints(), 0);
  // Said in the output too (not a failed request): a consumer computing frame after frame stops.
  vtkDataArray* unreadable =
      vtkArrayDownCast<vtkDataArray>(bad->GetFieldData()->GetAbstractArray("UnreadableFrame"));
  ASSERT_NE(unreadable, nullptr);
  EXPECT_EQ(unreadable->GetComponent(0, 0), 2);
  EXPECT_EQ(f.at(3)->GetNumberOfPoints(), 5);
  EXPECT_EQ(f.at(3)->GetFieldData()->GetAbstractArray("UnreadableFrame"), nullptr);
  EXPECT_EQ(f.log->Errors, "");

  writeText(f.dir.file("odd.series"), R"({"files":[{"name":"f0.las"}]})");
  f.source->SetDirectoryName(nullptr);
  f.source->SetFileName(f.dir.file("odd.series").c_str());
  f.at(0);
  EXPECT_NE(f.log->Errors.find("f0.las: unknown file extension"), std::string::npos)
      << f.log->Errors;
}

TEST(PointSequenceSource, NaNsAreDroppedWithACountAndEmptyFramesWarn)
{
  Fixture f;
  dp::PointCloud c = cloudOf(6, 0);
  c.points[4] = std::numeric_limits<double>::quiet_NaN();
  c.points[9] = -std::numeric_limits<double>::infinity();
  dp::writePLY(f.dir.file("a0.ply"), c);
  writeText(f.dir.file("a1.xyz"), "");
  f.source->SetDirectoryName(f.dir.path().c_str());
  EXPECT_EQ(f.at(0)->GetNumberOfPoints(), 4);
  EXPECT_EQ(f.source->GetNumberOfDroppedPoints(), 2);
  EXPECT_NE(f.log->Warnings.find("dropped 2 point(s) with NaN"), std::string::npos)
      << f.log->Warnings;
  EXPECT_EQ(f.at(1)->GetNumberOfPoints(), 0);
  EXPECT_EQ(f.log->Errors, "");
  EXPECT_NE(f.log->Warnings.find("a1.xyz: empty frame"), std::string::npos) << f.log->Warnings;
}

TEST(PointSequenceSource, NoInputAndMissingFolderAreErrors)
{
  Fixture f;
  EXPECT_EQ(f.source->GetNumberOfFrames(), -1);
  EXPECT_NE(f.log->Errors.find("No input"), std::string::npos);
  f.log->Errors.clear();
  f.source->SetDirectoryName(f.dir.file("nowhere").c_str());
  EXPECT_EQ(f.source->GetNumberOfFrames(), -1);
  EXPECT_NE(f.log->Errors.find("nowhere: folder does not exist"), std::string::npos)
      << f.log->Errors;
}

TEST(PointSequenceSource, VtkXmlFramesKeepTheirArraysAndPolygons)
{
  Fixture f;
  dp::PointCloud c = cloudOf(4, 1);
  c.points[7] = 1; // make a non-degenerate quad
  c.normals.assign(12, 0.0f);
  c.attributes.push_back({"weight", 1, {1, 2, 3, 4}});
  const std::int64_t quad[4] = {0, 1, 2, 3};
  c.addFace(quad, 4);
  dp::writePLY(f.dir.file("m.ply"), c);
  f.source->SetFileName(f.dir.file("m.ply").c_str());
  vtkPolyData* fromPly = f.at(0);
  EXPECT_EQ(fromPly->GetNumberOfPolys(), 1);
  ASSERT_NE(fromPly->GetPointData()->GetNormals(), nullptr);

  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetInputData(fromPly);
  writer->SetFileName(f.dir.file("m.vtp").c_str());
  ASSERT_EQ(writer->Write(), 1);
  f.source->SetFileName(f.dir.file("m.vtp").c_str());
  vtkPolyData* fromVtp = f.at(0);
  EXPECT_EQ(f.log->Errors, "");
  EXPECT_EQ(fromVtp->GetNumberOfPoints(), 4);
  EXPECT_EQ(fromVtp->GetNumberOfVerts(), 4);
  EXPECT_EQ(fromVtp->GetNumberOfPolys(), 1);
  ASSERT_NE(fromVtp->GetPointData()->GetArray("weight"), nullptr);
  EXPECT_EQ(fromVtp->GetPointData()->GetArray("weight")->GetTuple1(3), 4.0);

  writeText(f.dir.file("broken.vtp"), "<VTKFile type=\"PolyData\"><PolyData><Piece Number");
  f.source->SetFileName(f.dir.file("broken.vtp").c_str());
  f.at(0);
  EXPECT_EQ(f.log->Errors.find(f.dir.file("broken.vtp")) != std::string::npos, true)
      << f.log->Errors;
}

} // namespace
