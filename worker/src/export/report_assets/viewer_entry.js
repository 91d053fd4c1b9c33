// The run report's 3D view: csgtile's own glue around three.js (MIT, from npm), bundled by
// esbuild at configure time into report/viewer.js (worker/src/export/report_assets/embed.cmake).
//
// Defines window.csgtileViewer.create(container) → { show(glbBase64), dispose() }. The page
// (report.js) hands over a cell's GLB as base64 text: Chromium refuses fetch()/XHR of file://
// URLs, so the bytes arrive through a <script> that assigns them, never through a request.
//
// The GLB is in the cell's east-north-up frame with y up (export/tile_content.h), so the
// scene needs no transform: the camera looks from the south-east, above, at the model's
// bounding box.
import {
  AmbientLight,
  Box3,
  Color,
  DirectionalLight,
  HemisphereLight,
  PerspectiveCamera,
  Scene,
  Vector3,
  WebGLRenderer,
} from 'three';
import {GLTFLoader} from 'three/examples/jsm/loaders/GLTFLoader.js';
import {OrbitControls} from 'three/examples/jsm/controls/OrbitControls.js';

const kBackground = 0xf4f6f8;

function bytes_of_base64(text) {
  const binary = atob(text);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  return bytes.buffer;
}

function create(container) {
  const width = Math.max(container.clientWidth, 320);
  const height = Math.max(container.clientHeight, 240);
  // preserveDrawingBuffer keeps the last frame readable (screenshots, the page's own
  // blank-canvas check) although frames are drawn only on demand.
  const renderer = new WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(width, height);
  renderer.setClearColor(kBackground, 1);
  container.appendChild(renderer.domElement);

  const scene = new Scene();
  scene.background = new Color(kBackground);
  // A sun from the south-east and a weak fill from the north-west, so that walls facing
  // different ways get different shades.
  scene.add(new AmbientLight(0xffffff, 0.25));
  scene.add(new HemisphereLight(0xffffff, 0x555555, 0.9));
  const sun = new DirectionalLight(0xffffff, 2.2);
  sun.position.set(0.6, 1.0, 0.8);
  scene.add(sun);
  const fill = new DirectionalLight(0xffffff, 0.5);
  fill.position.set(-0.8, 0.4, -0.6);
  scene.add(fill);

  const camera = new PerspectiveCamera(45, width / height, 0.1, 1e6);
  const controls = new OrbitControls(camera, renderer.domElement);
  const render = () => renderer.render(scene, camera);
  controls.addEventListener('change', render);
  const resize = () => {
    const w = Math.max(container.clientWidth, 320), h = Math.max(container.clientHeight, 240);
    renderer.setSize(w, h);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    render();
  };
  window.addEventListener('resize', resize);

  let model = null;
  const loader = new GLTFLoader();

  function frame(object) {
    const box = new Box3().setFromObject(object);
    const centre = box.getCenter(new Vector3());
    const size = box.getSize(new Vector3());
    const radius = Math.max(size.length() / 2, 1e-3);
    const distance = radius / Math.sin((camera.fov * Math.PI) / 360);
    // glTF is y up and x east, so +z is south: look from the south-east, above.
    camera.position.copy(centre).add(new Vector3(0.55, 0.6, 0.6).normalize().multiplyScalar(distance));
    camera.near = distance / 1000;
    camera.far = distance * 100;
    camera.updateProjectionMatrix();
    controls.target.copy(centre);
    controls.update();
  }

  return {
    /// Replaces the shown model with the GLB in `base64`; resolves when it is drawn.
    show(base64) {
      return new Promise((resolve, reject) => {
        loader.parse(
          bytes_of_base64(base64),
          '',
          (gltf) => {
            if (model) scene.remove(model);
            model = gltf.scene;
            scene.add(model);
            frame(model);
            render();
            resolve();
          },
          (error) => reject(error instanceof Error ? error : new Error(String(error))));
      });
    },
    dispose() {
      window.removeEventListener('resize', resize);
      controls.dispose();
      renderer.dispose();
      renderer.domElement.remove();
    },
  };
}

window.csgtileViewer = {create};
