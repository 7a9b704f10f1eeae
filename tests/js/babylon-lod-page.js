// Browser side of babylon-lod.mjs: bundled by esbuild from node_modules and
// served by babylon-lod.mjs's local server. Exposes window.runLodTest().
import { Engine } from '@babylonjs/core/Engines/engine.js';
import { NullEngine } from '@babylonjs/core/Engines/nullEngine.js';
import { Scene } from '@babylonjs/core/scene.js';
import { ArcRotateCamera } from '@babylonjs/core/Cameras/arcRotateCamera.js';
import { HemisphericLight } from '@babylonjs/core/Lights/hemisphericLight.js';
import { Vector3 } from '@babylonjs/core/Maths/math.vector.js';
import { Mesh } from '@babylonjs/core/Meshes/mesh.js';
import { ImportMeshAsync, SceneLoader } from '@babylonjs/core/Loading/sceneLoader.js';
// Registers the glTF file loader plugin, the glTF 2.0 loader and its extensions (MSFT_lod among them).
import '@babylonjs/loaders/glTF/glTFFileLoader.js';
import '@babylonjs/loaders/glTF/2.0/index.js';

const NODE_POINTER = /^\/nodes\/(\d+)$/;

function pointers(obj) {
  return obj?._internalMetadata?.gltf?.pointers ?? [];
}

// Triangles of a Babylon node created for one glTF node: its own geometry (one
// primitive) or that of its direct primitive children (several primitives).
function nodeGeometry(bnode) {
  let triangles = 0;
  let vertices = 0;
  const parts = [bnode];
  for (const child of bnode.getChildren(undefined, true)) {
    if (pointers(child).some((p) => p.startsWith('/meshes/'))) parts.push(child);
  }
  for (const m of parts) {
    if (m instanceof Mesh && m.geometry) {
      triangles += m.getTotalIndices() / 3;
      vertices += m.getTotalVertices();
    }
  }
  return { triangles, vertices };
}

function makeEngine(useNull) {
  if (!useNull) {
    const canvas = document.getElementById('c');
    try {
      const engine = new Engine(canvas, false, { preserveDrawingBuffer: false, stencil: false });
      const gl = engine._gl;
      const dbg = gl.getExtension('WEBGL_debug_renderer_info');
      const renderer = dbg ? gl.getParameter(dbg.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
      return { engine, kind: `WebGL${engine.webGLVersion} (${renderer})` };
    } catch (e) {
      console.warn(`WebGL engine unavailable (${e.message}); falling back to NullEngine`);
    }
  }
  return { engine: new NullEngine(), kind: 'NullEngine' };
}

// chains: [{ key, nodes: [glTF node indices, coarse first] }]
window.runLodTest = async function runLodTest(url, chains, opts) {
  const { engine, kind } = makeEngine(opts.nullEngine);
  const scene = new Scene(engine);
  const camera = new ArcRotateCamera('cam', 0.8, 1.1, 3, Vector3.Zero(), scene);
  new HemisphericLight('light', new Vector3(0, 1, 0), scene);
  const chainOf = new Map(); // glTF node index -> chain key
  for (const c of chains) for (const n of c.nodes) chainOf.set(n, c.key);

  // MSFT_lod creates every level's node disabled and enables it once its data
  // is loaded (disposing the coarser one): record each chain's enablements.
  const enabled = Object.fromEntries(chains.map((c) => [c.key, []]));
  const watch = (bnode) => {
    bnode.onEnabledStateChangedObservable.add((isEnabled) => {
      if (!isEnabled) return;
      for (const p of pointers(bnode)) {
        const m = NODE_POINTER.exec(p);
        const key = m && chainOf.get(Number(m[1]));
        if (key === undefined || key === null) continue;
        enabled[key].push({ node: Number(m[1]), name: bnode.name, ...nodeGeometry(bnode), tMs: Math.round(performance.now() - t0) });
      }
    });
  };
  scene.onNewMeshAddedObservable.add((m) => {
    m.alwaysSelectAsActiveMesh = true; // no frustum culling: every enabled mesh is drawn
    watch(m);
  });
  scene.onNewTransformNodeAddedObservable.add(watch);

  const events = [];
  const snapshot = (indexLOD) => {
    const live = new Map(chains.map((c) => [c.key, []]));
    for (const bnode of [...scene.meshes, ...scene.transformNodes]) {
      if (bnode.isDisposed()) continue;
      for (const p of pointers(bnode)) {
        const m = NODE_POINTER.exec(p);
        if (!m) continue;
        const n = Number(m[1]);
        const key = chainOf.get(n);
        if (key === undefined) continue;
        const g = nodeGeometry(bnode);
        live.get(key).push({ node: n, name: bnode.name, enabled: bnode.isEnabled(false), ...g });
      }
    }
    events.push({
      indexLOD,
      chains: Object.fromEntries([...live.entries()]),
      tMs: Math.round(performance.now() - t0),
    });
  };

  let lodExtension = false;
  const done = new Promise((resolve, reject) => {
    SceneLoader.OnPluginActivatedObservable.addOnce((loader) => {
      if (loader.name !== 'gltf') {
        reject(new Error(`unexpected loader plugin ${loader.name}`));
        return;
      }
      loader.onExtensionLoadedObservable.add((ext) => {
        if (ext.name !== 'MSFT_lod') return;
        lodExtension = ext.enabled;
        ext.onNodeLODsLoadedObservable.add((indexLOD) => {
          try {
            snapshot(indexLOD);
          } catch (e) {
            reject(e);
          }
        });
      });
      loader.onCompleteObservable.addOnce(() => resolve());
      loader.onErrorObservable.addOnce((reason) => reject(reason instanceof Error ? reason : new Error(String(reason))));
    });
  });

  const t0 = performance.now();
  const load = ImportMeshAsync(url, scene, {
    pluginExtension: '.glb',
    pluginOptions: {
      gltf: {
        useRangeRequests: true, // fetch one level's byte range at a time, coarse first
        extensionOptions: { MSFT_lod: { maxLODsToLoad: 1000 } },
      },
    },
  });
  await Promise.all([load, done]);
  // Frame the whole model and draw one more frame with the finest levels.
  const ext = scene.getWorldExtends();
  const center = ext.min.add(ext.max).scale(0.5);
  camera.setTarget(center);
  camera.radius = Math.max(1e-6, ext.max.subtract(ext.min).length()) * 1.5;
  await scene.whenReadyAsync();
  scene.render();
  const result = {
    engine: kind,
    babylonVersion: Engine.Version,
    lodExtension,
    events,
    enabled,
    finalDrawnTriangles: scene.getActiveIndices() / 3,
  };
  scene.dispose();
  engine.dispose();
  return result;
};
window.lodPageReady = true;
