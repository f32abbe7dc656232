#include "curvemesh/geom/model.hpp"

namespace cm::geom {

std::string to_string(ShapeType t) {
  switch (t) {
    case ShapeType::kPoint: return "point";
    case ShapeType::kLine: return "line";
    case ShapeType::kCircle: return "circle";
    case ShapeType::kEllipse: return "ellipse";
    case ShapeType::kBSplineCurve: return "bspline_curve";
    case ShapeType::kBezierCurve: return "bezier_curve";
    case ShapeType::kOtherCurve: return "curve";
    case ShapeType::kPlane: return "plane";
    case ShapeType::kCylinder: return "cylinder";
    case ShapeType::kCone: return "cone";
    case ShapeType::kSphere: return "sphere";
    case ShapeType::kTorus: return "torus";
    case ShapeType::kBSplineSurface: return "bspline_surface";
    case ShapeType::kBezierSurface: return "bezier_surface";
    case ShapeType::kSurfaceOfRevolution: return "surface_of_revolution";
    case ShapeType::kSurfaceOfExtrusion: return "surface_of_extrusion";
    case ShapeType::kOffsetSurface: return "offset_surface";
    case ShapeType::kOtherSurface: return "surface";
    case ShapeType::kSolid: return "solid";
  }
  return "unknown";
}

}  // namespace cm::geom
