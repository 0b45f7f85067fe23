// The minimum distance between robot and environment (state.distance): a line from a to b
// and a label with its value in mm at the line's middle, kept in place after every render.

import * as THREE from 'three';

export class DistanceView {
  constructor(view, labelLayer) {
    this.view = view;
    this.geom = new THREE.BufferGeometry();
    this.geom.setAttribute('position', new THREE.Float32BufferAttribute([0, 0, 0, 0, 0, 0], 3));
    this.line = new THREE.Line(this.geom, new THREE.LineBasicMaterial({ color: 0xd81b60, depthTest: false }));
    this.line.renderOrder = 3;
    this.line.visible = false;
    this.line.frustumCulled = false;
    view.scene.add(this.line);
    const dot = new THREE.SphereGeometry(0.006, 12, 8);
    const dotMat = new THREE.MeshBasicMaterial({ color: 0xd81b60, depthTest: false });
    this.ends = [new THREE.Mesh(dot, dotMat), new THREE.Mesh(dot, dotMat)];
    for (const e of this.ends) { e.visible = false; e.renderOrder = 3; view.scene.add(e); }
    this.label = document.createElement('div');
    this.label.className = 'label distance';
    this.label.hidden = true;
    labelLayer.appendChild(this.label);
    this.mid = new THREE.Vector3();
    this.text = null;
    view.afterRender.push(() => this.#place());
  }

  update(d) {
    const show = !!d && Array.isArray(d.a) && Array.isArray(d.b);
    this.line.visible = show;
    for (const e of this.ends) e.visible = show;
    this.label.hidden = !show;
    if (!show) {
      this.text = null;
      return;
    }
    const pos = this.geom.attributes.position;
    pos.setXYZ(0, d.a[0], d.a[1], d.a[2]);
    pos.setXYZ(1, d.b[0], d.b[1], d.b[2]);
    pos.needsUpdate = true;
    this.ends[0].position.fromArray(d.a);
    this.ends[1].position.fromArray(d.b);
    this.mid.set((d.a[0] + d.b[0]) / 2, (d.a[1] + d.b[1]) / 2, (d.a[2] + d.b[2]) / 2);
    const between = [d.body, d.obstacle].filter(Boolean).join(' ↔ ');
    this.text = `${(d.value * 1000).toFixed(1)} mm${between ? ` (${between})` : ''}`;
    this.label.textContent = this.text;
    this.view.requestRender();
  }

  #place() {
    if (this.label.hidden) return;
    const s = this.view.toScreen(this.mid);
    if (!s) { this.label.style.display = 'none'; return; }
    this.label.style.display = '';
    this.label.style.transform = `translate(${s.x + 8}px, ${s.y - 10}px)`;
  }
}
