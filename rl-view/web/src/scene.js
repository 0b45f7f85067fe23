// The three.js view: renderer, camera with orbit/pan/zoom, lights, ground grid, world axes.
//
// World is z-up like the robots. The view renders on demand (requestRender) from one
// requestAnimationFrame loop, so an idle viewer costs no GPU time; `frames` counts renders.

import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

THREE.Object3D.DEFAULT_UP.set(0, 0, 1);

export class View {
  constructor(container) {
    this.container = container;
    this.frames = 0;
    this.dirty = true;
    this.afterRender = [];

    this.renderer = new THREE.WebGLRenderer({ antialias: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    container.appendChild(this.renderer.domElement);

    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0xe9edf2);

    this.camera = new THREE.PerspectiveCamera(40, 1, 0.01, 200);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(1.7, -1.9, 1.3);

    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.target.set(0, 0, 0.4);
    this.controls.update();
    this.controls.addEventListener('change', () => this.requestRender());
    this.userMovedCamera = false;
    this.controls.addEventListener('start', () => { this.userMovedCamera = true; });

    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8090a0, 1.4));
    const key = new THREE.DirectionalLight(0xffffff, 2.2);
    key.position.set(2.5, -3, 5);
    this.scene.add(key);
    const fill = new THREE.DirectionalLight(0xffffff, 0.7);
    fill.position.set(-3, 2, 2);
    this.scene.add(fill);

    // Ground grid in the xy plane: 4 m, 10 cm cells, a darker line every metre.
    const fine = new THREE.GridHelper(4, 40, 0xc3cad3, 0xd3d9e0);
    fine.rotation.x = Math.PI / 2;
    this.scene.add(fine);
    const coarse = new THREE.GridHelper(4, 4, 0x9aa5b2, 0x9aa5b2);
    coarse.rotation.x = Math.PI / 2;
    coarse.position.z = 0.0005;
    this.scene.add(coarse);

    this.worldAxes = new THREE.AxesHelper(0.3);
    this.worldAxes.material.depthTest = false;
    this.worldAxes.renderOrder = 1;
    this.scene.add(this.worldAxes);

    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
    const loop = () => {
      if (this.dirty) {
        this.dirty = false;
        this.renderer.render(this.scene, this.camera);
        this.frames += 1;
        for (const f of this.afterRender) f();
      }
      requestAnimationFrame(loop);
    };
    requestAnimationFrame(loop);
  }

  requestRender() {
    this.dirty = true;
  }

  resize() {
    const w = Math.max(1, this.container.clientWidth);
    const h = Math.max(1, this.container.clientHeight);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  /** Points the camera at `box` (a THREE.Box3) unless the user has moved it already. */
  frame(box) {
    if (this.userMovedCamera || box.isEmpty()) return;
    const center = box.getCenter(new THREE.Vector3());
    // Far enough that the box's bounding sphere fits the narrower field of view.
    const radius = box.getSize(new THREE.Vector3()).length() / 2;
    const vfov = THREE.MathUtils.degToRad(this.camera.fov);
    const hfov = 2 * Math.atan(Math.tan(vfov / 2) * this.camera.aspect);
    const dist = Math.max(0.8, 1.25 * radius / Math.sin(Math.min(vfov, hfov) / 2));
    const dir = new THREE.Vector3(1.0, -1.15, 0.75).normalize();
    this.controls.target.copy(center);
    this.camera.position.copy(center).addScaledVector(dir, dist);
    this.camera.near = dist / 200;
    this.camera.far = dist * 50;
    this.camera.updateProjectionMatrix();
    this.controls.update();
    this.requestRender();
  }

  /** Screen position (CSS pixels inside the container) of a world point; null if behind. */
  toScreen(p) {
    const v = p.clone().project(this.camera);
    if (v.z > 1) return null;
    return {
      x: (v.x * 0.5 + 0.5) * this.container.clientWidth,
      y: (-v.y * 0.5 + 0.5) * this.container.clientHeight,
    };
  }
}

/** Sets an Object3D's pose from [x, y, z, qx, qy, qz, qw]. */
export function setPose(obj, pose) {
  obj.position.set(pose[0], pose[1], pose[2]);
  obj.quaternion.set(pose[3], pose[4], pose[5], pose[6]);
}
