import { resolve } from "node:path";
import { defineConfig } from "vite";

// Dev-only build of bench.html (a synthetic tree, no server) for benchmarks/web_render.py
// and for looking at the exploration view without a session. Never shipped in dist/.
export default defineConfig({
  base: "./",
  build: {
    outDir: "dist-bench",
    emptyOutDir: true,
    target: "es2022",
    rollupOptions: { input: resolve(import.meta.dirname, "bench.html") },
  },
});
