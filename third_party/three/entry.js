// The parts of three.js the tactus report uses, exposed as the global THREE (an IIFE bundle, so
// the page loads it with a plain <script> from file://, where ES modules are blocked).
export {
  AmbientLight, BufferAttribute, BufferGeometry, Color, DirectionalLight, DoubleSide, Float32BufferAttribute,
  Mesh, MeshBasicMaterial, MeshLambertMaterial, PerspectiveCamera, Raycaster, Scene, SphereGeometry,
  Vector2, Vector3, WebGLRenderer, LineSegments, LineBasicMaterial, EdgesGeometry, Box3, Sphere, Group,
} from "three";
export { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
