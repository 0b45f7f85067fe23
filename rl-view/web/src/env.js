// The environment's obstacles (scene.env.bodies): fixed shapes at their world poses.

import * as THREE from 'three';
import { buildShape } from './shapes.js';
import { setPose } from './scene.js';

export class EnvView {
  constructor(view, env, changed) {
    this.view = view;
    this.root = new THREE.Group();
    this.root.name = 'env';
    this.meshes = { pending: 0, loaded: 0, failed: 0, errors: [] };
    const manager = new THREE.LoadingManager();
    const material = new THREE.MeshStandardMaterial({
      color: 0x6f8fb3, roughness: 0.7, transparent: true, opacity: 0.85,
    });
    for (const body of (env && env.bodies) || []) {
      const g = new THREE.Group();
      g.name = body.name;
      if (Array.isArray(body.pose)) setPose(g, body.pose);
      for (const shape of body.shapes || []) {
        if (shape.kind === 'mesh') this.meshes.pending += 1;
        g.add(buildShape(shape, material, manager, (err) => {
          this.meshes.pending -= 1;
          if (err) {
            this.meshes.failed += 1;
            this.meshes.errors.push(`${shape.url}: ${err.message || err}`);
          } else {
            this.meshes.loaded += 1;
          }
          changed({});
        }));
      }
      this.root.add(g);
    }
    view.scene.add(this.root);
  }

  dispose() {
    this.view.scene.remove(this.root);
  }
}
