// Geometry from the scene JSON: primitive shapes and mesh files (STL, OBJ, COLLADA).
//
// Cylinders and capsules lie along z, as in the scene JSON (three.js builds them along y).
// Mesh files go through one LoadingManager per model so the page knows when all are in.

import * as THREE from 'three';
import { STLLoader } from 'three/examples/jsm/loaders/STLLoader.js';
import { OBJLoader } from 'three/examples/jsm/loaders/OBJLoader.js';
import { ColladaLoader } from 'three/examples/jsm/loaders/ColladaLoader.js';
import { setPose } from './scene.js';

/** The mesh format of a file name or URL by its extension: "stl", "obj", "dae" or null. */
export function meshFormat(url) {
  const m = /\.(stl|obj|dae)(?:[?#].*)?$/i.exec(url);
  return m ? m[1].toLowerCase() : null;
}

/**
 * Loads a mesh file and calls done(object) or done(null, error). `material` (may be null)
 * replaces the file's own materials for STL and OBJ; COLLADA keeps the file's materials.
 */
export function loadMesh(url, format, manager, material, done) {
  const fail = (err) => done(null, err instanceof Error ? err : new Error(String(err)));
  switch (format) {
    case 'stl':
      new STLLoader(manager).load(url, (geom) => {
        geom.computeVertexNormals();
        done(new THREE.Mesh(geom, material || new THREE.MeshStandardMaterial({ color: 0xb8bec6 })));
      }, undefined, fail);
      break;
    case 'obj':
      new OBJLoader(manager).load(url, (group) => {
        if (material) group.traverse((o) => { if (o.isMesh) o.material = material; });
        done(group);
      }, undefined, fail);
      break;
    case 'dae':
      // Like urdf-loader: keep the file's unit scale, drop the loader's up-axis rotation (the
      // vertices are in the link frame whatever the file's <up_axis>).
      new ColladaLoader(manager).load(url, (dae) => {
        dae.scene.position.set(0, 0, 0);
        dae.scene.quaternion.identity();
        done(dae.scene);
      }, undefined, fail);
      break;
    default:
      fail(new Error(`no loader for mesh ${url} (format ${format})`));
  }
}

/**
 * One shape of the scene JSON as an Object3D in its body's frame. Mesh shapes are filled in
 * when their file has loaded; `onMesh(err)` is called then (err null on success). Inline
 * meshes (triangles in the JSON) are drawn at once and reported done just after.
 */
export function buildShape(shape, material, manager, onMesh) {
  const holder = new THREE.Group();
  if (Array.isArray(shape.pose) && shape.pose.length === 7) setPose(holder, shape.pose);
  let geom = null;
  let alongZ = false;
  switch (shape.kind) {
    case 'box':
      geom = new THREE.BoxGeometry(shape.size[0], shape.size[1], shape.size[2]);
      break;
    case 'sphere':
      geom = new THREE.SphereGeometry(shape.radius, 32, 16);
      break;
    case 'cylinder':
      geom = new THREE.CylinderGeometry(shape.radius, shape.radius, shape.length, 32);
      alongZ = true;
      break;
    case 'capsule':
      geom = new THREE.CapsuleGeometry(shape.radius, shape.length, 8, 24);
      alongZ = true;
      break;
    case 'cone':
      geom = new THREE.ConeGeometry(shape.radius, shape.length, 32);
      alongZ = true;
      break;
    case 'plane': {
      // A half-space n·x <= offset: drawn as a 4 m square on its boundary plane.
      const n = new THREE.Vector3().fromArray(shape.normal || [0, 0, 1]).normalize();
      geom = new THREE.PlaneGeometry(4, 4);
      const mesh = new THREE.Mesh(geom, material);
      mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), n);
      mesh.position.copy(n).multiplyScalar(shape.offset || 0);
      holder.add(mesh);
      return holder;
    }
    case 'mesh': {
      if (Array.isArray(shape.vertices) && Array.isArray(shape.triangles)) {
        holder.add(inlineMesh(shape, material));
        // Drawn already; reported like a loaded file (the caller counted it as pending), from
        // a task of its own as a file's load would be.
        queueMicrotask(() => onMesh(null));
        return holder;
      }
      const format = shape.format || meshFormat(shape.url);
      loadMesh(shape.url, format, manager, material, (obj, err) => {
        if (obj) {
          if (Array.isArray(shape.scale)) obj.scale.multiply(new THREE.Vector3().fromArray(shape.scale));
          holder.add(obj);
        }
        onMesh(err || null);
      });
      return holder;
    }
    default:
      console.warn(`rl view: shape kind ${shape.kind} is not drawn`);
      return holder;
  }
  const mesh = new THREE.Mesh(geom, material);
  if (alongZ) mesh.rotation.x = Math.PI / 2;
  holder.add(mesh);
  return holder;
}

/** A mesh whose triangles the scene JSON carries inline (VRML faces, MoveIt meshes). */
function inlineMesh(shape, material) {
  const geom = new THREE.BufferGeometry();
  geom.setAttribute('position', new THREE.Float32BufferAttribute(shape.vertices.flat(), 3));
  geom.setIndex(shape.triangles.flat());
  geom.computeVertexNormals();
  const mesh = new THREE.Mesh(geom, material);
  if (Array.isArray(shape.scale)) mesh.scale.set(shape.scale[0], shape.scale[1], shape.scale[2]);
  return mesh;
}

/** Every mesh under `root`, with its material(s) as an array. */
export function meshesOf(root) {
  const out = [];
  root.traverse((o) => { if (o.isMesh) out.push(o); });
  return out;
}
