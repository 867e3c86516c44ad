#include "semrec/infer/onnx_session.h"

#include <cstdlib>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::infer {
namespace {

// Builds Y = Relu(X + B) with X: [N, 3] (N dynamic), B = (1, -2, 0.5), using
// Debian's python3-onnx.
fs::path BuildTinyModel(const fs::path& dir) {
  const fs::path script = dir / "make.py";
  const fs::path model = dir / "tiny.onnx";
  semrec::testing::WriteText(script, R"(
import sys, onnx
from onnx import helper, TensorProto
b = helper.make_tensor("B", TensorProto.FLOAT, [3], [1.0, -2.0, 0.5])
g = helper.make_graph(
    [helper.make_node("Add", ["X", "B"], ["S"]), helper.make_node("Relu", ["S"], ["Y"])],
    "tiny", [helper.make_tensor_value_info("X", TensorProto.FLOAT, ["N", 3])],
    [helper.make_tensor_value_info("Y", TensorProto.FLOAT, ["N", 3])], [b])
m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 13)])
m.ir_version = 8
onnx.checker.check_model(m)
onnx.save(m, sys.argv[1])
)");
  const std::string cmd =
      "/usr/bin/python3 " + script.string() + " " + model.string();
  if (std::system(cmd.c_str()) != 0) return {};
  return model;
}

TEST(OnnxSession, RunsATinyModelExactly) {
  semrec::testing::TempDir dir;
  const fs::path model = BuildTinyModel(dir.path());
  ASSERT_FALSE(model.empty()) << "python3-onnx could not build the test model";
  OnnxSession session(model);
  ASSERT_EQ(session.inputs().size(), 1u);
  EXPECT_EQ(session.inputs()[0].name, "X");
  EXPECT_EQ(session.inputs()[0].shape, (std::vector<int64_t>{-1, 3}));
  const auto out = session.Run({{"X", Tensor{{2, 3}, {0, 0, 0, 1, 3, -1}}}});
  const Tensor& y = out.at("Y");
  EXPECT_EQ(y.shape, (std::vector<int64_t>{2, 3}));
  EXPECT_EQ(y.data, (std::vector<float>{1, 0, 0.5f, 2, 1, 0}));
}

TEST(OnnxSession, ClearErrorsForBadInputs) {
  semrec::testing::TempDir dir;
  const fs::path model = BuildTinyModel(dir.path());
  ASSERT_FALSE(model.empty());
  OnnxSession session(model);
  try {
    session.Run({{"X", Tensor{{2, 4}, std::vector<float>(8)}}});
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "tiny.onnx: input 'X' has shape [2,4], the model "
                  "expects [-1,3]"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(session.Run({}), InvalidArgument);
  EXPECT_THROW(session.Run({{"X", Tensor{{1, 3}, {1, 2, 3}}},
                            {"Z", Tensor::Zeros({1})}}),
               InvalidArgument);
  EXPECT_THROW(session.Run({{"X", Tensor{{1, 3}, {1, 2}}}}), InvalidArgument);
}

TEST(OnnxSession, MissingOrCorruptModel) {
  semrec::testing::TempDir dir;
  EXPECT_THROW(OnnxSession(dir / "absent.onnx"), IoError);
  semrec::testing::WriteText(dir / "bad.onnx", "not a model");
  try {
    OnnxSession session(dir / "bad.onnx");
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.onnx"), std::string::npos);
  }
}

TEST(OnnxSession, RuntimeIsTheAssembledOne) {
  EXPECT_EQ(OnnxSession::RuntimeVersion(), "1.30.0");
}

}  // namespace
}  // namespace semrec::infer
