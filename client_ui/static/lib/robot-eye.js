// The robot's-eye view drawn in the browser: what the simulated robot's camera sees, from the scene description
// and a pose, with the server camera's mount, intrinsics, clipping planes and lighting (scene-three.js), so the
// server need not render a camera nobody else watches. tests/e2e/test_robot_eye_fidelity.py holds it to the
// server's frames (masks of walls, floor and lines, IoU >= 0.9).

import * as THREE from "three";
import { SURFACES, aimRobotEye, buildScene, placeRobot, robotEyeCamera } from "./scene-three.js";

/** A material that writes one surface code into the red channel, unshaded and unconverted. */
function codeMaterial(code, { depthWrite = true } = {}) {
  return new THREE.ShaderMaterial({
    vertexShader: "void main() { gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0); }",
    fragmentShader: `void main() { gl_FragColor = vec4(${(code / 255).toFixed(6)}, 0.0, 0.0, 1.0); }`, // data, not text: shader source
    depthWrite,
  });
}

export class RobotEyeRenderer {
  #renderer;
  #world;
  #three;
  #eye;
  #camera;

  /**
   * Draws into canvas (throws where WebGL is missing). `width_px`/`height_px` default to the camera's own
   * resolution; another size keeps the field of view (the picture is the same, finer or coarser).
   */
  constructor(canvas, scene, { width_px, height_px, antialias = false, preserveDrawingBuffer = false } = {}) {
    this.#camera = scene.camera;
    this.#renderer = new THREE.WebGLRenderer({ canvas, antialias, preserveDrawingBuffer, powerPreference: "low-power" });
    this.#renderer.setPixelRatio(1);
    this.#renderer.setClearColor(new THREE.Color(...scene.camera.background_rgba.slice(0, 3)), 1);
    this.#renderer.setSize(width_px ?? scene.camera.width_px, height_px ?? scene.camera.height_px, false);
    this.#world = buildScene(scene);
    this.#three = new THREE.Scene();
    this.#three.add(this.#world.lab, this.#world.robot);
    this.#eye = robotEyeCamera(scene.camera);
  }

  /** The drawing buffer's size in pixels, {width, height}. */
  get size() {
    const size = this.#renderer.getDrawingBufferSize(new THREE.Vector2());
    return { width: size.x, height: size.y };
  }

  /** Draws the view of a robot at pose ({x_m, y_m, theta_rad}); the robot's own body is drawn as the server does. */
  render(pose) {
    placeRobot(this.#world.robot, pose);
    aimRobotEye(this.#eye, this.#camera, pose);
    this.#renderer.render(this.#three, this.#eye);
  }

  /**
   * Draws the same view with each surface in a flat code (SURFACES: background, floor, mark, solid, robot) and
   * returns one code per pixel, rows from the top: the same meshes, camera and layering as render(), only the
   * materials differ, so the masks it gives are those of the picture render() draws.
   */
  renderSurfaces(pose) {
    const originals = new Map();
    const codes = new Map();
    const codeOf = (surface, depthWrite) => {
      const key = `${surface}:${depthWrite}`;
      if (!codes.has(key)) codes.set(key, codeMaterial(SURFACES[surface] ?? 0, { depthWrite }));
      return codes.get(key);
    };
    this.#three.traverse((object) => {
      if (!object.isMesh) return;
      originals.set(object, object.material);
      object.material = codeOf(object.userData.surface, object.material.depthWrite);
    });
    const clear = this.#renderer.getClearColor(new THREE.Color());
    this.#renderer.setClearColor(0x000000, 1);
    try {
      this.render(pose);
      const rgba = this.readPixels();
      const surfaces = new Uint8Array(rgba.length / 4);
      for (let i = 0; i < surfaces.length; i += 1) surfaces[i] = rgba[i * 4];
      return surfaces;
    } finally {
      for (const [object, material] of originals) object.material = material;
      for (const material of codes.values()) material.dispose();
      this.#renderer.setClearColor(clear, 1);
    }
  }

  /** The pixels drawn last, RGBA, rows from the top (call in the same task as render, or keep the buffer). */
  readPixels() {
    const { width, height } = this.size;
    const gl = this.#renderer.getContext();
    const bottomUp = new Uint8Array(width * height * 4);
    gl.readPixels(0, 0, width, height, gl.RGBA, gl.UNSIGNED_BYTE, bottomUp);
    const rows = new Uint8Array(bottomUp.length);
    const stride = width * 4;
    for (let y = 0; y < height; y += 1) rows.set(bottomUp.subarray((height - 1 - y) * stride, (height - y) * stride), y * stride);
    return rows;
  }

  dispose() {
    this.#world.dispose();
    this.#renderer.dispose();
  }
}
