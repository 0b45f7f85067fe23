// A plan shown before and while it runs (scene.plan: `rl view SCENARIO.xml`, `rl view --path`):
// translucent ghosts of the robot at the start (green) and the goal (orange), at the body poses
// the server computed (the same forward kinematics and placement as the collision checker),
// and the trail of the tool along the path (a line through the tool positions the server
// sampled, at most 1° apart in every joint). Both stay while the path plays.

import * as THREE from 'three';
import { buildShape } from './shapes.js';
import { setPose } from './scene.js';

const GHOSTS = [['start', 0x2e9d4a], ['goal', 0xef7d00]];

export class PlanView {
  constructor(view) {
    this.view = view;
    this.root = new THREE.Group();
    this.root.name = 'plan';
    this.ghosts = {};
    this.trailPoints = 0;
    view.scene.add(this.root);
  }

  /** Replaces what is shown with `scene.plan` (nothing when the scene has none). */
  build(scene) {
    this.clear();
    const plan = scene.plan;
    if (!plan) return;
    const model = scene.models.find((m) => m.index === plan.model);
    if (!model) return;
    const manager = new THREE.LoadingManager();
    for (const [which, color] of GHOSTS) {
      const end = plan[which];
      if (!end || !Array.isArray(end.bodies)) continue;
      const material = new THREE.MeshStandardMaterial({
        color, transparent: true, opacity: 0.28, depthWrite: false, roughness: 0.8,
      });
      const g = new THREE.Group();
      g.name = `${which} ghost`;
      let bodies = 0;
      model.bodies.forEach((b, i) => {
        const pose = end.bodies[i];
        if (!Array.isArray(pose) || !(b.shapes || []).length) return;
        const body = new THREE.Group();
        setPose(body, pose);
        for (const shape of b.shapes) {
          body.add(buildShape(shape, material, manager, () => this.view.requestRender()));
        }
        g.add(body);
        bodies += 1;
      });
      this.ghosts[which] = bodies;
      this.root.add(g);
    }
    const pts = (plan.trail || []).filter((p) => Array.isArray(p) && p.length === 3);
    if (pts.length >= 2) {
      const geom = new THREE.BufferGeometry().setFromPoints(pts.map((p) => new THREE.Vector3(...p)));
      const line = new THREE.Line(geom, new THREE.LineBasicMaterial({ color: 0xd81b60 }));
      line.name = 'trail';
      this.root.add(line);
      this.trailPoints = pts.length;
    }
    this.view.requestRender();
  }

  clear() {
    this.root.traverse((o) => {
      if (o.geometry) o.geometry.dispose();
      if (o.material) o.material.dispose();
    });
    this.root.clear();
    this.ghosts = {};
    this.trailPoints = 0;
  }

  /** Test hook: bodies per ghost and points of the trail drawn. */
  shown() {
    return { start: this.ghosts.start || 0, goal: this.ghosts.goal || 0, trail: this.trailPoints };
  }
}
