// The built-in walker scene (scenes.h "walker"): its geometry, bond types, muscles and warm-up.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "motion_model_estimation/core/simulator.h"
#include "scene_parts.h"

namespace mme {
namespace scene_parts {
namespace {

// ------------------------------------------------------------------------------------------
// walker: the horse of section 4.4 with its 35 markers at 50 Hz (5 per leg: leg_<fl|fr|hl|hr>_0
// shoulder/hip .. _4 hoof; 15 body/head markers body_00..body_14). It trots on a floor, driven
// by known muscle controllers (docs/scenes.md "The walker": the laws, figures and limits).
//  - trunk, neck and head: one triangular prism truss along x, 6 cross-sections (x = -0.6 ..
//    1.4 m, step 0.4 m), equilateral of edge 0.4 m: two bottom "rails" (y = +-0.2 m) and a top
//    ridge; every rectangular face braced by one diagonal. Sections 0..3 are the trunk (the legs
//    hang from the rails of sections 0 and 3), 4 and 5 the neck and head; the tail (body_08) sits
//    on three soft springs behind section 0.
//  - legs: 4 segments of 0.4 m inclined +20, 0, -20, 0 degrees (forwards) from the vertical in
//    the leg's plane, which splays outwards by 10 degrees: joints of 160 degrees, _3 on the
//    line from the hip to the hoof. Flexions: "knee" at _1 and _2 (stiff), "fetlock" at _3
//    (soft: the lift muscle holds it), "hip"/"hip_hind" between the upper segment and the rail
//    one bay inwards (the fore-aft swing), and "splay" from the other hip of the pair to every
//    joint of the leg (holds the leg in its plane; it does not resist the swing).
//  - ground: a `floor` bond on every hoof (a conditional bond: it acts only below z = 0).
//  - controllers (all muscles are pure actuators: no stiffness or damping of their own):
//    * rhythm: a muscle along the tail's top spring reads that spring's elongation speed and
//      pushes the way the tail moves (negative damping, saturated by tanh): a limit cycle of the
//      tail bobbing at ~1.6 Hz. Every leg muscle reads the tail's top spring.
//    * swing (one per leg, _2 to the rail one bay inwards): a servo on the length of a soft
//      "reach" spring along it (hidden unit 0), whose target the stride moves (hidden unit 1).
//    * lift (one per leg, _2 to the hoof): a servo on a soft "cannon" spring along it, whose
//      target folds the fetlock while the leg swings and stretches it a little in stance.
//    Types come in pairs for the two diagonals (a: fl + hr, b: fr + hl) whose stride weights are
//    each other's negatives: a diagonal trot. A servo, not a passive joint, carries the load:
//    a passive fetlock stiff enough to stand would need several times the weight to fold.
// The walker starts mid-stride: the model's initial state is where a 2-s warm-up from the
// standing pose (tail pushed up) ends. 80 substeps: the stiff contact and servos (~1000 rad/s)
// need them for an integration that has converged (with 20 the motion was chaotic at round-off
// and a different gait); the gait stays the same with 100 or 160.
constexpr double kWalkerEdgeM = 0.4;                       // trunk bays and cross-sections
constexpr double kWalkerSegmentM = 0.4;                    // leg segments
constexpr double kWalkerLegTiltRad = 20.0 * kPi / 180.0;   // segment inclinations
constexpr double kWalkerSplayRad = 10.0 * kPi / 180.0;     // leg plane from the vertical
constexpr int kWalkerSubsteps = 80;
constexpr int kWalkerWarmupFrames = 100;
constexpr double kWalkerLegMassKg[5] = {8.0, 6.0, 5.0, 4.0, 4.0};  // shoulder/hip .. hoof
constexpr double kWalkerTrunkMassKg = 10.0;
constexpr double kWalkerTailMassKg = 4.0;
constexpr double kWalkerNeckMassKg = 2.0;
constexpr double kWalkerHeadMassKg = 1.0;
constexpr double kWalkerTailKickMps = 0.5;  // the tail's initial upward speed
// Controller weights (docs/scenes.md "The walker"): the tail's drive [s/m]; the stride units
// read the tail's top spring (elongation [1/m], speed [s/m], centred on its mean elongation
// [m]); the servos read their reach or cannon spring; outputs are dimensionless (the gains are
// in N).
constexpr double kTailDriveGainN = 4.43, kTailDriveSpeed = -20.0, kTailMeanM = 0.04;
constexpr double kSwingGainN = 2740.0, kSwingStrideZ = -99.6, kSwingStrideS = 0.9;
constexpr double kReachServoZ = 28.0, kReachServoS = 0.5, kReachOut = 10.0, kSwingOut = 2.73;
constexpr double kLiftGainN = 2290.0, kLiftStrideZ = -100.0, kLiftStrideS = 0.11;
constexpr double kCannonServoZ = 40.0, kCannonServoS = 0.5, kCannonOut = 10.0;
constexpr double kLiftOut = 4.74, kLiftBias = 4.47;

/// A muscle type that is a pure actuator (stiffness, rest length and damping present and 0),
/// every parameter fixed.
BondType walkerMuscleType(const std::string& name, double gain_n, int inputs, int hidden,
                          const std::vector<double>& network) {
  BondType type;
  type.name = name;
  type.kind = BondKind::kMuscle;
  type.param(kStiffness) = valueParam(0.0);
  type.param(kRestLength) = valueParam(0.0);
  type.param(kDamping) = valueParam(0.0);
  type.param(kGain) = valueParam(gain_n);
  type.network_inputs = inputs;
  type.network_hidden = hidden;
  for (double w : network) type.network.push_back(valueParam(w));
  return type;
}

/// Installs a bond and names it; returns its index.
int addNamedBond(Model* model, int type, int a, int b, const std::string& name) {
  addBond(model, type, a, b);
  model->bonds.back().name = name;
  return static_cast<int>(model->bonds.size()) - 1;
}

/// Where the walker's particles are: legs [fl, fr, hl, hr][hip .. hoof], prism sections [rear ..
/// head][left rail, right rail, ridge], the tail, and each hip's rail one bay inwards (the hip
/// flexion's third point and the swing muscle's).
struct WalkerLayout {
  static constexpr int kSections = 6;
  int leg[4][5];
  int section[kSections][3];
  int tail = -1;
  int inner_rail[4];
};

constexpr const char* kWalkerLegNames[4] = {"fl", "fr", "hl", "hr"};
constexpr double kWalkerLegX[4] = {0.6, 0.6, -0.6, -0.6};
constexpr double kWalkerLegY[4] = {0.2, -0.2, 0.2, -0.2};

/// The legs' 20 markers, then the body's (its rails and ridge, the tail, the neck and the head).
WalkerLayout placeWalkerParticles(Model* model) {
  WalkerLayout w;
  const double e = kWalkerEdgeM, seg = kWalkerSegmentM, splay = kWalkerSplayRad;
  const double leg_angles[4] = {kWalkerLegTiltRad, 0.0, -kWalkerLegTiltRad, 0.0};
  double rail_z = 0.0;
  for (double a : leg_angles) rail_z += seg * std::cos(a) * std::cos(splay);
  const double ridge_z = rail_z + e * std::sqrt(0.75);
  char name[32];
  for (int l = 0; l < 4; ++l) {
    const double side = kWalkerLegY[l] > 0 ? 1.0 : -1.0;
    Eigen::Vector3d x(kWalkerLegX[l], kWalkerLegY[l], rail_z);
    for (int k = 0; k < 5; ++k) {
      std::snprintf(name, sizeof(name), "leg_%s_%d", kWalkerLegNames[l], k);
      if (k == 4) x.z() = 0.0;  // on the floor despite rounding
      w.leg[l][k] = addParticle(model, x, {name, kWalkerLegMassKg[k]});
      if (k == 4) break;
      const double down = seg * std::cos(leg_angles[k]);
      x += Eigen::Vector3d(seg * std::sin(leg_angles[k]), side * down * std::sin(splay), -down * std::cos(splay));
    }
  }
  w.section[0][0] = w.leg[2][0];
  w.section[0][1] = w.leg[3][0];
  w.section[3][0] = w.leg[0][0];
  w.section[3][1] = w.leg[1][0];
  auto sectionPoint = [&](int s, int corner) {
    const double x = -0.6 + e * s;
    if (corner == 2) return Eigen::Vector3d(x, 0.0, ridge_z);
    return Eigen::Vector3d(x, corner == 0 ? 0.2 : -0.2, rail_z);
  };
  int next_body = 0;
  auto addBody = [&](const Eigen::Vector3d& x, double mass_kg) {
    std::snprintf(name, sizeof(name), "body_%02d", next_body++);
    return addParticle(model, x, {name, mass_kg});
  };
  for (int s = 0; s < 4; ++s) w.section[s][2] = addBody(sectionPoint(s, 2), kWalkerTrunkMassKg);  // 00-03
  for (int corner = 0; corner < 2; ++corner)  // 04-07: rails between the legs
    for (int s = 1; s <= 2; ++s) w.section[s][corner] = addBody(sectionPoint(s, corner), kWalkerTrunkMassKg);
  // Tail (body_08): apex of a regular tetrahedron on the rear face.
  const Eigen::Vector3d rear = (sectionPoint(0, 0) + sectionPoint(0, 1) + sectionPoint(0, 2)) / 3.0;
  w.tail = addBody(rear - Eigen::Vector3d(e * std::sqrt(2.0 / 3.0), 0.0, 0.0), kWalkerTailMassKg);
  for (int s = 4; s < WalkerLayout::kSections; ++s)  // 09-11 neck, 12-14 head
    for (int corner = 0; corner < 3; ++corner)
      w.section[s][corner] = addBody(sectionPoint(s, corner), s == 4 ? kWalkerNeckMassKg : kWalkerHeadMassKg);
  const int inner_rail[4] = {w.section[2][0], w.section[2][1], w.section[1][0], w.section[1][1]};
  std::copy(inner_rail, inner_rail + 4, w.inner_rail);
  return w;
}

enum WalkerSpring { kLeg, kBody, kBodyBrace, kNeck, kNeckBrace, kTail, kCannon, kReachFore, kReachHind, kSpringTypes };
enum WalkerFlexion { kKnee, kFetlock, kHipFore, kHipHind, kSplay, kFlexionTypes };

/// The walker's bond types: springs (stiffness, damping, rest length free: that of the unloaded
/// geometry), flexions (stiffness, rest angle free; damping fixed) and the ground.
struct WalkerTypes {
  int spring[kSpringTypes];
  int flexion[kFlexionTypes];
  int ground = -1;
};

WalkerTypes addWalkerTypes(Model* model, const WalkerLayout& w) {
  std::vector<Eigen::Vector3d> x0;
  for (const Particle& p : model->particles) x0.push_back(p.position_m);
  auto dist = [&](int a, int b) { return (x0[a] - x0[b]).norm(); };
  auto angle = [&](int a, int b, int c) {
    return std::acos((x0[a] - x0[b]).normalized().dot((x0[c] - x0[b]).normalized()));
  };
  const double e = kWalkerEdgeM, seg = kWalkerSegmentM;
  struct SpringSpec {
    const char* name;
    double rest_length, stiffness, damping;
  };
  const double k_leg = 3.0e5, k_body = 3.0e5;
  const SpringSpec springs[kSpringTypes] = {
      {"leg_spring", seg, k_leg, 0.0003 * k_leg},
      {"body_spring", e, k_body, 0.0003 * k_body},
      {"body_brace", e * std::sqrt(2.0), 0.5 * k_body, 0.00015 * k_body},
      {"neck_spring", e, 0.4 * k_body, 0.0001 * k_body},
      {"neck_brace", e * std::sqrt(2.0), 0.25 * k_body, 0.00005 * k_body},
      {"tail_spring", e, 1200.0, 2.0},
      // The servos' sensors: soft springs along the lift and swing muscles.
      {"cannon", dist(w.leg[0][2], w.leg[0][4]), 2000.0, 5.0},
      {"reach_fore", dist(w.leg[0][2], w.inner_rail[0]), 2000.0, 5.0},
      {"reach_hind", dist(w.leg[2][2], w.inner_rail[2]), 2000.0, 5.0}};
  WalkerTypes types;
  for (int t = 0; t < kSpringTypes; ++t) {
    BondType type;
    type.name = springs[t].name;
    type.param(kStiffness) = freeMagnitude(springs[t].stiffness);
    type.param(kDamping) = freeMagnitude(springs[t].damping);
    type.param(kRestLength) = freeLength(springs[t].rest_length);
    types.spring[t] = addBondType(model, type);
  }
  struct FlexionSpec {
    const char* name;
    double rest_angle, stiffness, damping;
  };
  const FlexionSpec flexions[kFlexionTypes] = {
      {"knee", angle(w.leg[0][0], w.leg[0][1], w.leg[0][2]), 1.0e5, 100.0},
      {"fetlock", angle(w.leg[0][2], w.leg[0][3], w.leg[0][4]), 200.0, 10.0},
      {"hip", angle(w.leg[0][1], w.leg[0][0], w.inner_rail[0]), 7460.0, 100.0},
      {"hip_hind", angle(w.leg[2][1], w.leg[2][0], w.inner_rail[2]), 7460.0, 100.0},
      {"splay", angle(w.leg[1][0], w.leg[0][0], w.leg[0][4]), 3.0e4, 100.0}};
  for (int t = 0; t < kFlexionTypes; ++t) {
    BondType type;
    type.name = flexions[t].name;
    type.kind = BondKind::kFlexion;
    type.param(kStiffness) = freeMagnitude(flexions[t].stiffness);
    type.param(kRestAngle) = boundedParam(flexions[t].rest_angle, 0.5 * flexions[t].rest_angle,
                                          std::min(kPi, 2.0 * flexions[t].rest_angle));
    type.param(kDamping) = valueParam(flexions[t].damping);
    types.flexion[t] = addBondType(model, type);
  }
  // Ground contact, free: stiffness, damping, friction; the floor's height (0) and contact
  // depth fixed. The damping and friction grow over the first 0.3 mm of the 4.5-6 mm a stance
  // hoof sinks: without that the force jumps at touch-down and gradient fits stall on the jumps
  // it makes in the motion (docs/scenes.md "Identifying the walker").
  BondType ground;
  ground.name = "ground";
  ground.kind = BondKind::kFloor;
  ground.param(kStiffness) = freeMagnitude(5.0e5);
  ground.param(kDamping) = freeMagnitude(2000.0);
  ground.param(kFriction) = freeMagnitude(4000.0);
  ground.param(kHeight) = valueParam(0.0);
  ground.param(kContactDepth) = valueParam(3.0e-4);
  types.ground = addBondType(model, ground);
  return types;
}

/// Legs: segments, joints, hips, splay (from the other hip of the pair), ground contact.
void addWalkerLegBonds(Model* model, const WalkerLayout& w, const WalkerTypes& types) {
  for (int l = 0; l < 4; ++l) {
    const int other_hip = w.leg[l ^ 1][0];
    for (int k = 0; k < 4; ++k) addBond(model, types.spring[kLeg], w.leg[l][k], w.leg[l][k + 1]);
    for (int k = 1; k <= 3; ++k)
      addBond(model, types.flexion[k == 3 ? kFetlock : kKnee], w.leg[l][k - 1], w.leg[l][k], w.leg[l][k + 1]);
    addBond(model, types.flexion[kWalkerLegX[l] > 0 ? kHipFore : kHipHind], w.leg[l][1], w.leg[l][0],
            w.inner_rail[l]);
    for (int k = 1; k <= 4; ++k) addBond(model, types.flexion[kSplay], other_hip, w.leg[l][0], w.leg[l][k]);
    addBond(model, types.ground, w.leg[l][4]);
  }
}

/// Prism: cross-section triangles, then per bay 3 longitudinal edges and 3 face diagonals.
void addWalkerPrismBonds(Model* model, const WalkerLayout& w, const WalkerTypes& types) {
  for (int s = 0; s < WalkerLayout::kSections; ++s) {
    const int edge = s < 4 ? types.spring[kBody] : types.spring[kNeck];
    addBond(model, edge, w.section[s][0], w.section[s][1]);
    addBond(model, edge, w.section[s][0], w.section[s][2]);
    addBond(model, edge, w.section[s][1], w.section[s][2]);
  }
  for (int s = 0; s + 1 < WalkerLayout::kSections; ++s) {
    const int edge = s < 3 ? types.spring[kBody] : types.spring[kNeck];
    const int brace = s < 3 ? types.spring[kBodyBrace] : types.spring[kNeckBrace];
    for (int corner = 0; corner < 3; ++corner) addBond(model, edge, w.section[s][corner], w.section[s + 1][corner]);
    addBond(model, brace, w.section[s][0], w.section[s + 1][2]);
    addBond(model, brace, w.section[s][1], w.section[s + 1][2]);
    addBond(model, brace, w.section[s][0], w.section[s + 1][1]);
  }
}

/// The muscles: the tail's drive (y = w s_top), then per diagonal a swing and a lift muscle
/// reading (tail top, sensor); hidden 0 = the servo on the sensor's length, hidden 1 = the
/// stride (sign +-1 per diagonal); y = servo_out h0 + stride_out h1 + b2.
void addWalkerMuscles(Model* model, const WalkerLayout& w, int tail_top, const int cannon[4],
                      const int reach[4]) {
  const int tail_drive = addBondType(model, walkerMuscleType("tail_drive", kTailDriveGainN, 1, 0,
                                                             {0.0, kTailDriveSpeed, 0.0}));
  addBond(model, tail_drive, w.tail, w.section[0][2]);
  model->bonds.back().inputs = {tail_top};
  int swing[2], lift[2];
  for (int d = 0; d < 2; ++d) {
    const double sign = d == 0 ? 1.0 : -1.0;
    const std::string diagonal = d == 0 ? "_a" : "_b";
    swing[d] = addBondType(model, walkerMuscleType("swing" + diagonal, kSwingGainN, 2, 2,
                                                   {0.0, kReachServoZ, 0.0, kReachServoS,                   // w1_0_*
                                                    sign * kSwingStrideZ, 0.0, sign * kSwingStrideS, 0.0,   // w1_1_*
                                                    0.0, -sign * kSwingStrideZ * kTailMeanM,                // b1
                                                    kReachOut, kSwingOut, 0.0}));                           // w2, b2
    lift[d] = addBondType(model, walkerMuscleType("lift" + diagonal, kLiftGainN, 2, 2,
                                                  {0.0, kCannonServoZ, 0.0, kCannonServoS,                  // w1_0_*
                                                   sign * kLiftStrideZ, 0.0, sign * kLiftStrideS, 0.0,      // w1_1_*
                                                   0.0, -sign * kLiftStrideZ * kTailMeanM,                  // b1
                                                   kCannonOut, kLiftOut, kLiftBias}));                      // w2, b2
  }
  // A swing muscle's tension pulls the knee backwards on a fore leg, forwards on a hind one: the
  // left legs (fl, hl) take swing_a, the right ones swing_b, so that fl and hr push back while
  // fr and hl swing forward. The lifts go by diagonal.
  const int lift_diagonal[4] = {0, 1, 1, 0};
  for (int l = 0; l < 4; ++l) {
    addBond(model, swing[kWalkerLegY[l] > 0 ? 0 : 1], w.leg[l][2], w.inner_rail[l]);
    model->bonds.back().inputs = {tail_top, reach[l]};
    addBond(model, lift[lift_diagonal[l]], w.leg[l][2], w.leg[l][4]);
    model->bonds.back().inputs = {tail_top, cannon[l]};
  }
}

/// Warm-up from the standing pose with the tail pushed up; the scene starts where it ends.
void warmUpWalker(Model* model, int tail) {
  model->particles[tail].velocity_mps = Eigen::Vector3d(0.0, 0.0, kWalkerTailKickMps);
  Simulator simulator(*model);
  State state = simulator.initialState();
  for (int f = 0; f < kWalkerWarmupFrames; ++f) simulator.stepFrame(&state, 1.0 / model->frame_rate_hz);
  for (size_t i = 0; i < model->particles.size(); ++i) {
    model->particles[i].position_m = state.x_m[i];
    model->particles[i].velocity_mps = state.v_mps[i];
  }
}

}  // namespace

Scene makeWalker() {
  Scene scene;
  Model& model = scene.model;
  model.frame_rate_hz = 50.0;
  model.substeps = kWalkerSubsteps;
  setGravity(&model, Eigen::Vector3d(0.0, 0.0, -9.81));
  const WalkerLayout w = placeWalkerParticles(&model);
  const WalkerTypes types = addWalkerTypes(&model, w);
  addWalkerLegBonds(&model, w, types);
  // The servos' sensor springs: cannons (_2 to the hoof), reaches (_2 to the inner rail).
  int cannon[4], reach[4];
  for (int l = 0; l < 4; ++l)
    cannon[l] = addNamedBond(&model, types.spring[kCannon], w.leg[l][2], w.leg[l][4],
                             std::string("cannon_") + kWalkerLegNames[l]);
  for (int l = 0; l < 4; ++l)
    reach[l] = addNamedBond(&model, types.spring[kWalkerLegX[l] > 0 ? kReachFore : kReachHind], w.leg[l][2],
                            w.inner_rail[l], std::string("reach_") + kWalkerLegNames[l]);
  addWalkerPrismBonds(&model, w, types);
  // Tail: three soft springs to the rear section, named (the top one is every muscle's input).
  const char* tail_names[3] = {"tail_left", "tail_right", "tail_top"};
  int tail_top = -1;
  for (int corner = 0; corner < 3; ++corner)
    tail_top = addNamedBond(&model, types.spring[kTail], w.tail, w.section[0][corner], tail_names[corner]);
  addWalkerMuscles(&model, w, tail_top, cannon, reach);
  warmUpWalker(&model, w.tail);
  scene.default_frames = 250;
  return scene;
}

}  // namespace scene_parts
}  // namespace mme
