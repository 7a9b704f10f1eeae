// Browser side of babylon-morph.mjs: bundled by esbuild from node_modules and
// served by babylon-morph.mjs's local server. Exposes window.runMorphTest().
import { Engine } from '@babylonjs/core/Engines/engine.js';
import { NullEngine } from '@babylonjs/core/Engines/nullEngine.js';
import { Scene } from '@babylonjs/core/scene.js';
import { ArcRotateCamera } from '@babylonjs/core/Cameras/arcRotateCamera.js';
import { HemisphericLight } from '@babylonjs/core/Lights/hemisphericLight.js';
import { Vector3 } from '@babylonjs/core/Maths/math.vector.js';
import { ImportMeshAsync, SceneLoader } from '@babylonjs/core/Loading/sceneLoader.js';
// Animation playback (scene.beginAnimation / AnimationGroup.start need it).
import '@babylonjs/core/Animations/animatable.js';
import '@babylonjs/loaders/glTF/glTFFileLoader.js';
import '@babylonjs/loaders/glTF/2.0/index.js';

function makeEngine() {
  try {
    const engine = new Engine(document.getElementById('c'), false, { preserveDrawingBuffer: true, stencil: false });
    return { engine, kind: `WebGL${engine.webGLVersion}` };
  } catch (e) {
    console.warn(`WebGL engine unavailable (${e.message}); falling back to NullEngine`);
    return { engine: new NullEngine(), kind: 'NullEngine' };
  }
}

// Every mesh with a morph target manager: name, enabled, target names and influences.
function morphed(scene) {
  return scene.meshes
    .filter((m) => m.morphTargetManager && !m.isDisposed())
    .map((m) => {
      const mtm = m.morphTargetManager;
      const targets = [];
      for (let i = 0; i < mtm.numTargets; i++) targets.push(mtm.getTarget(i));
      return {
        name: m.name,
        enabled: m.isEnabled(),
        vertices: m.getTotalVertices(),
        targets: targets.map((t) => t.name),
        influences: targets.map((t) => t.influence),
      };
    });
}

// Loads `url` (every MSFT_lod level), then plays the animation group
// `animation` and samples every morphed mesh's influences at `times`
// (seconds), rendering a frame at each.
window.runMorphTest = async function runMorphTest(url, animation, times) {
  const { engine, kind } = makeEngine();
  const scene = new Scene(engine);
  const camera = new ArcRotateCamera('cam', 0.8, 1.1, 5, Vector3.Zero(), scene);
  new HemisphericLight('light', new Vector3(0, 1, 0), scene);
  const done = new Promise((resolve, reject) => {
    SceneLoader.OnPluginActivatedObservable.addOnce((loader) => {
      loader.onCompleteObservable.addOnce(() => resolve());
      loader.onErrorObservable.addOnce((reason) => reject(reason instanceof Error ? reason : new Error(String(reason))));
    });
  });
  await Promise.all([
    ImportMeshAsync(url, scene, {
      pluginExtension: '.glb',
      pluginOptions: { gltf: { extensionOptions: { MSFT_lod: { maxLODsToLoad: 1000 } } } },
    }),
    done,
  ]);
  const ext = scene.getWorldExtends();
  camera.setTarget(ext.min.add(ext.max).scale(0.5));
  camera.radius = Math.max(1e-6, ext.max.subtract(ext.min).length()) * 1.5;
  await scene.whenReadyAsync();
  const loaded = morphed(scene);
  const groups = scene.animationGroups.map((g) => g.name);
  const group = scene.animationGroups.find((g) => g.name === animation);
  const samples = [];
  if (group) {
    for (const g of scene.animationGroups) g.stop();
    group.start(false, 1.0);
    group.pause();
    for (const t of times) {
      group.goToFrame(t * 60); // the glTF loader keys animations at 60 frames per second
      scene.render();
      samples.push({ t, meshes: morphed(scene) });
    }
    group.stop();
  }
  scene.render();
  const result = { engine: kind, babylonVersion: Engine.Version, groups, loaded, samples };
  scene.dispose();
  engine.dispose();
  return result;
};
window.morphPageReady = true;
