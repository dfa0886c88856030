// MeshRelationalConv forward pass.
#include "engine/model/mesh_relational_conv.h"

#include <torch/nn/functional/activation.h>

namespace dynscope {

MeshRelationalConvImpl::MeshRelationalConvImpl(const MeshRelationalConvOptions& o) {
  const int64_t c = o.out_channels();
  to_sender = register_module("to_sender", PointConv(PointConvOptions(o.in_channels(), c)
                                                         .c_mid(o.c_mid())
                                                         .pos_channels(o.pos_channels())
                                                         .position_scale(o.position_scale())));
  to_receiver = register_module(
      "to_receiver",
      PointConv(PointConvOptions(c, c).c_mid(o.c_mid()).normalize(true).position_scale(
          o.position_scale())));
  to_vertex = register_module("to_vertex", PointConv(PointConvOptions(c, c)
                                                         .c_mid(o.c_mid())
                                                         .pos_channels(o.pos_channels())
                                                         .normalize(true)
                                                         .position_scale(o.position_scale())));
}

torch::Tensor MeshRelationalConvImpl::forward(const torch::Tensor& x, const torch::Tensor& vertices,
                                              const MeshTensors& mesh) {
  const torch::Tensor sender =
      torch::relu(to_sender->forward(mesh.points, vertices, x, mesh.face_vertices));
  const torch::Tensor receiver =
      torch::relu(to_receiver->forward(mesh.points, mesh.points, sender, mesh.senders));
  return to_vertex->forward(vertices, mesh.points, receiver, mesh.vertex_points);
}

}  // namespace dynscope
