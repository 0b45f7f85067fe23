// Bundles the page into dist/ (index.html, viewer.js, style.css, THIRD_PARTY_LICENSES.txt).
// Run by scripts/build-viewer after `npm ci`; the output is committed so that building the
// Rust crates needs no Node.js.

import * as esbuild from 'esbuild';
import { readFileSync, writeFileSync, mkdirSync, copyFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const dist = join(here, 'dist');
mkdirSync(dist, { recursive: true });

await esbuild.build({
  entryPoints: [join(here, 'src', 'main.js')],
  bundle: true,
  minify: true,
  format: 'iife',
  target: ['es2022'],
  outfile: join(dist, 'viewer.js'),
  legalComments: 'none', // the licences are in THIRD_PARTY_LICENSES.txt beside the bundle
  logLevel: 'warning',
});
await esbuild.build({
  entryPoints: [join(here, 'src', 'style.css')],
  bundle: true,
  minify: true,
  outfile: join(dist, 'style.css'),
  logLevel: 'warning',
});
copyFileSync(join(here, 'src', 'index.html'), join(dist, 'index.html'));

const pkg = (name) => JSON.parse(readFileSync(join(here, 'node_modules', name, 'package.json'), 'utf8'));
const three = pkg('three');
const urdf = pkg('urdf-loader');
const urdfReadme = readFileSync(join(here, 'node_modules', 'urdf-loader', 'README.md'), 'utf8');
const notice = urdfReadme.slice(urdfReadme.indexOf('Copyright'));
const licences = [
  'rl view\'s page (rl-view/web/dist/viewer.js) bundles the following npm packages.',
  '',
  '='.repeat(78),
  `three ${three.version} (${three.license}) - ${three.homepage}`,
  '='.repeat(78),
  readFileSync(join(here, 'node_modules', 'three', 'LICENSE'), 'utf8').trim(),
  '',
  '='.repeat(78),
  `urdf-loader ${urdf.version} (${urdf.license}) - https://github.com/gkjohnson/urdf-loaders`,
  '='.repeat(78),
  'Notice from the package\'s README.md:',
  '',
  notice.trim(),
  '',
  'The package does not ship the licence text; it is the Apache License 2.0:',
  '',
  readFileSync(join(here, 'licenses', 'Apache-2.0.txt'), 'utf8').trim(),
  '',
].join('\n');
writeFileSync(join(dist, 'THIRD_PARTY_LICENSES.txt'), licences);
console.log(`rl-view/web/dist: bundled with three ${three.version}, urdf-loader ${urdf.version}`);
