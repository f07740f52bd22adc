import { defineConfig } from "vitest/config";

// The server serves dist/ at "/" (docs/app.md), so assets are referenced relatively.
export default defineConfig({
  base: "./",
  build: { outDir: "dist", emptyOutDir: true, target: "es2022", sourcemap: true },
  server: {
    // `npm run dev` proxies the API to a local `groupwise serve` (default port 8000).
    proxy: {
      "/api": "http://127.0.0.1:8000",
      "/clips": "http://127.0.0.1:8000",
    },
  },
  test: { include: ["test/**/*.test.ts"], environment: "node" },
});
