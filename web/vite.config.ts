import { resolve } from "node:path";
import { defineConfig } from "vitest/config";

// The build goes into the Python package (src/groupwise/static/, shipped as package data),
// which the server serves at "/" (docs/app.md), so assets are referenced relatively.
export default defineConfig({
  base: "./",
  build: {
    outDir: resolve(import.meta.dirname, "../src/groupwise/static"),
    emptyOutDir: true,
    target: "es2022",
    sourcemap: true,
  },
  server: {
    // `npm run dev` proxies the API to a local `groupwise serve` (default port 8000).
    proxy: {
      "/api": "http://127.0.0.1:8000",
      "/clips": "http://127.0.0.1:8000",
    },
  },
  test: { include: ["test/**/*.test.ts"], environment: "node" },
});
