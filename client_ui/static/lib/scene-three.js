// three.js objects built from a robot's scene description (GET /api/robots/<r>/scene, the skill server's GetScene),
// shaded the way the server's camera shades them, so a view drawn in the browser matches the robot's JPEG camera:
// the same floor, marks, walls and robot, the same camera mount and intrinsics, the same lighting formula
// (CameraModel in protos/telelab/v1/robot.proto). The world frame is the lab's: x east, y north, z up, metres.
// No DOM here: the panels own canvases and renderers.

import * as THREE from "three";

const UP = new THREE.Vector3(0, 0, 1);
/** What a mesh shows, in mesh.userData.surface, as the server's render_surfaces() codes them. */
export const SURFACES = Object.freeze({ background: 0, floor: 1, mark: 2, solid: 3, robot: 4 });
const CYLINDER_SEGMENTS = 32;

/**
 * Where the robot's camera is and a point 1 m along its optical axis, for a robot at pose (world frame, metres):
 * the mount is mount_forward_m ahead of the centre along the heading, mount_height_m above the floor, pitched by
 * mount_pitch_rad. The same arithmetic as skill_server/sim/camera.py `camera_eye_and_target`.
 */
export function cameraEyeAndTarget(camera, pose) {
  const cosT = Math.cos(pose.theta_rad);
  const sinT = Math.sin(pose.theta_rad);
  const eye = [pose.x_m + camera.mount_forward_m * cosT, pose.y_m + camera.mount_forward_m * sinT, camera.mount_height_m];
  const cosP = Math.cos(camera.mount_pitch_rad);
  const sinP = Math.sin(camera.mount_pitch_rad);
  return { eye, target: [eye[0] + cosT * cosP, eye[1] + sinT * cosP, eye[2] + sinP] };
}

/** The brightness the server's renderer gives a surface of unit normal n (the CameraModel's formula). */
export function brightness(camera, [nx, ny, nz]) {
  const [lx, ly, lz] = camera.light_direction;
  const nDotL = nx * lx + ny * ly + nz * lz;
  const rz = 2 * nDotL * nz - lz;
  const lit = camera.light_diffuse * Math.max(0, nDotL) + camera.light_specular * Math.max(0, rz) ** camera.specular_exponent;
  return camera.light_ambient + Math.min(lit, 1 - camera.light_ambient);
}

const VERTEX_SHADER = `
varying vec3 vWorldNormal;
void main() {
  vWorldNormal = normalize(mat3(modelMatrix) * normal);
  gl_Position = projectionMatrix * viewMatrix * modelMatrix * vec4(position, 1.0);
}`;

// The server's formula per fragment, with the world normal (the robot turns, so nothing can be baked in).
// No colour-space conversion: the values written are the server's, byte for byte up to rounding.
const FRAGMENT_SHADER = `
uniform vec3 albedo;
uniform vec3 lightDirection;
uniform float ambient;
uniform float diffuse;
uniform float specular;
uniform float specularExponent;
varying vec3 vWorldNormal;
void main() {
  vec3 n = normalize(vWorldNormal);
  float nDotL = dot(n, lightDirection);
  float rz = 2.0 * nDotL * n.z - lightDirection.z;
  float lit = diffuse * max(0.0, nDotL) + specular * pow(max(0.0, rz), specularExponent);
  gl_FragColor = vec4(albedo * (ambient + min(lit, 1.0 - ambient)), 1.0);
}`;

/** A material that shades like the server's camera (colours as the description gives them, 0..1). */
export function serverShadedMaterial(rgba, camera) {
  return new THREE.ShaderMaterial({
    uniforms: {
      albedo: { value: new THREE.Vector3(rgba[0], rgba[1], rgba[2]) },
      lightDirection: { value: new THREE.Vector3(...camera.light_direction) },
      ambient: { value: camera.light_ambient },
      diffuse: { value: camera.light_diffuse },
      specular: { value: camera.light_specular },
      specularExponent: { value: camera.specular_exponent },
    },
    vertexShader: VERTEX_SHADER,
    fragmentShader: FRAGMENT_SHADER,
  });
}

/** An upright cylinder geometry along z (three's cylinders run along y; URDF's and the scene's along z). */
function zCylinder(radius, length) {
  return new THREE.CylinderGeometry(radius, radius, length, CYLINDER_SEGMENTS).rotateX(Math.PI / 2);
}

/**
 * The lab's static objects and the robot, from a scene description.
 * Returns {lab: Group (floor, marks, walls, obstacles), robot: Group (its parts in its own frame; place it with
 * placeRobot), bounds: {minX, maxX, minY, maxY} (the floor), maxZ (the tallest block's top)}, dispose()}.
 */
export function buildScene(scene) {
  const camera = scene.camera;
  const materials = new Map();
  const material = (rgba) => {
    const key = rgba.join(",");
    if (!materials.has(key)) materials.set(key, serverShadedMaterial(rgba, camera));
    return materials.get(key);
  };
  const lab = new THREE.Group();
  lab.name = "lab";
  const floor = scene.floor;
  lab.add(patchMesh(floor, material(floor.rgba), 0, "floor"));
  // Marks are painted over the floor in order, as the server layers them a hair apart: each draws after the
  // previous without writing depth, so a later mark covers an earlier one and walls still hide them.
  scene.marks.forEach((mark, index) => {
    const paint = material(mark.rgba).clone();
    paint.depthWrite = false;
    lab.add(patchMesh(mark, paint, 1 + index, "mark"));
  });
  for (const block of scene.blocks) {
    const mesh = new THREE.Mesh(new THREE.BoxGeometry(2 * block.half_x_m, 2 * block.half_y_m, block.height_m),
      material(block.rgba));
    mesh.position.set(block.center_x_m, block.center_y_m, block.height_m / 2);
    mesh.rotation.z = block.yaw_rad;
    mesh.name = block.name;
    mesh.userData.surface = "solid";
    lab.add(mesh);
  }
  for (const cylinder of scene.cylinders) {
    const mesh = new THREE.Mesh(zCylinder(cylinder.radius_m, cylinder.height_m), material(cylinder.rgba));
    mesh.position.set(cylinder.center_x_m, cylinder.center_y_m, cylinder.height_m / 2);
    mesh.name = cylinder.name;
    mesh.userData.surface = "solid";
    lab.add(mesh);
  }
  const robot = new THREE.Group();
  robot.name = "robot";
  for (const part of scene.robot_parts) {
    const [sx, sy, sz] = part.size_m;
    const geometry = part.shape === "box" ? new THREE.BoxGeometry(sx, sy, sz)
      : part.shape === "cylinder" ? zCylinder(sx, sz)
        : part.shape === "sphere" ? new THREE.SphereGeometry(sx, 16, 12) : null;
    if (!geometry) continue; // a shape this page does not know: left out rather than guessed
    const mesh = new THREE.Mesh(geometry, material(part.rgba));
    mesh.position.set(...part.position_m);
    mesh.quaternion.set(...part.orientation_xyzw);
    mesh.name = part.link;
    mesh.userData.surface = "robot";
    robot.add(mesh);
  }
  const bounds = {
    minX: floor.center_x_m - floor.half_x_m, maxX: floor.center_x_m + floor.half_x_m,
    minY: floor.center_y_m - floor.half_y_m, maxY: floor.center_y_m + floor.half_y_m,
    maxZ: Math.max(0, ...scene.blocks.map((b) => b.height_m), ...scene.cylinders.map((c) => c.height_m)),
  };
  return {
    lab,
    robot,
    bounds,
    dispose() {
      const shared = new Set(materials.values());
      for (const group of [lab, robot]) {
        group.traverse((object) => {
          object.geometry?.dispose();
          if (object.material && !shared.has(object.material)) object.material.dispose();
        });
      }
      for (const each of shared) each.dispose();
    },
  };
}

function patchMesh(patch, patchMaterial, renderOrder, surface) {
  const mesh = new THREE.Mesh(new THREE.PlaneGeometry(2 * patch.half_x_m, 2 * patch.half_y_m), patchMaterial);
  mesh.position.set(patch.center_x_m, patch.center_y_m, patch.top_z_m);
  mesh.renderOrder = renderOrder;
  mesh.name = patch.kind;
  mesh.userData.surface = surface;
  return mesh;
}

/** Puts the robot's group at a pose on the floor. */
export function placeRobot(robot, pose) {
  robot.position.set(pose.x_m, pose.y_m, 0);
  robot.rotation.set(0, 0, pose.theta_rad);
}

/** A perspective camera with the robot camera's intrinsics (vertical field of view, aspect, clipping planes, and
 *  where in each pixel the server samples). */
export function robotEyeCamera(camera) {
  const eye = new THREE.PerspectiveCamera(camera.vfov_deg, camera.width_px / camera.height_px, camera.near_m,
    camera.far_m);
  eye.up.copy(UP);
  // The server samples each pixel off its centre (TinyRenderer: at a corner); WebGL samples centres, so the view is
  // shifted by that much, in the camera's own pixels (at another canvas size the shift scales with them).
  const dx = Number(camera.sample_offset_x_px) || 0;
  const dy = Number(camera.sample_offset_y_px) || 0;
  if (dx || dy) eye.setViewOffset(camera.width_px, camera.height_px, dx, dy, camera.width_px, camera.height_px);
  return eye;
}

/** Aims a robotEyeCamera from the mount of a robot at pose. */
export function aimRobotEye(eye, camera, pose) {
  const { eye: position, target } = cameraEyeAndTarget(camera, pose);
  eye.position.set(...position);
  eye.up.copy(UP);
  eye.lookAt(...target);
  eye.updateMatrixWorld();
}
