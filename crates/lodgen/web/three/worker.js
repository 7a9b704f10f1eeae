// lodgen-three's decoder worker (a module worker; index.js starts it with
// `new Worker(new URL("./worker.js", import.meta.url), { type: "module" })`,
// a form Vite, webpack 5 and Parcel bundle with its imports): the
// LODGEN_progressive stream decoded off the page's main thread (remote.js).
import { MeshoptDecoder } from "meshoptimizer/decoder";
import { serveDecoder } from "./remote.js";

serveDecoder(self, MeshoptDecoder);
