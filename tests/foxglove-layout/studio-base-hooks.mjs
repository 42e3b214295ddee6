// Module hooks (node:module register) that let Node load a few modules of @foxglove/studio-base
// 1.48.0 as Foxglove's own bundler did: the package ships its sources as ES modules in files that
// Node would read as CommonJS, imports them without extensions, reads some files as text through
// webpack's "?raw" suffix (TypeScript's lib files and the user-script helpers, which it ships only
// as .d.ts), imports "typescript/lib/typescript", and imports two packages it does not depend on:
// @foxglove/den (unpublished; the transformer uses one helper of it) and @mui/material (for a
// React hook that is never called here). Nothing here changes what the loaded modules do.

import fs from "node:fs";
import { fileURLToPath, pathToFileURL } from "node:url";

const STUDIO_BASE = "/node_modules/@foxglove/studio-base/src/";

// @foxglove/den/collection's filterMap: map, keeping the truthy results.
const DEN_COLLECTION =
  "export function filterMap(items, fn) { const out = []; let i = 0; " +
  "for (const item of items) { const v = fn(item, i++); if (v) out.push(v); } " +
  "return out; }";

const MUI_MATERIAL =
  'export function useTheme() { throw new Error("@mui/material is not installed here"); }';

function inStudioBase(url) {
  return url?.startsWith("file:") && fileURLToPath(url).includes(STUDIO_BASE);
}

export async function resolve(specifier, context, nextResolve) {
  const { parentURL } = context;
  if (!inStudioBase(parentURL)) {
    return nextResolve(specifier, context);
  }
  if (specifier === "@foxglove/den/collection") {
    return {
      url: `data:text/javascript,${encodeURIComponent(DEN_COLLECTION)}`,
      shortCircuit: true,
    };
  }
  // util/globalConstants.js, which the transformer imports for its output prefix, also holds a
  // React hook for a theme; the hook is never called here.
  if (specifier === "@mui/material") {
    return { url: `data:text/javascript,${encodeURIComponent(MUI_MATERIAL)}`, shortCircuit: true };
  }
  if (specifier === "typescript/lib/typescript") {
    return nextResolve("typescript", context);
  }
  if (specifier.endsWith("?raw")) {
    const bare = specifier.slice(0, -"?raw".length);
    let path;
    if (bare.startsWith(".")) {
      path = fileURLToPath(new URL(bare, parentURL));
    } else {
      // typescript/lib/lib.*.d.ts: a file of the typescript package
      const [name, ...rest] = bare.split("/");
      const main = fileURLToPath((await nextResolve(name, context)).url);
      const root = main.slice(0, main.lastIndexOf(`/node_modules/${name}/`));
      path = `${root}/node_modules/${name}/${rest.join("/")}`;
    }
    // The package ships the user-script helpers (userUtils/*.ts) as declarations only.
    if (!fs.existsSync(path) && path.endsWith(".ts")) {
      path = `${path.slice(0, -3)}.d.ts`;
    }
    return { url: `${pathToFileURL(path).href}?raw`, shortCircuit: true };
  }
  if (specifier.startsWith(".") && !/\.(m?js|json)$/.test(specifier)) {
    return { url: new URL(`${specifier}.js`, parentURL).href, shortCircuit: true };
  }
  return nextResolve(specifier, context);
}

export async function load(url, context, nextLoad) {
  if (url.startsWith("file:") && url.endsWith("?raw")) {
    const text = fs.readFileSync(fileURLToPath(url.slice(0, -"?raw".length)), "utf8");
    return {
      format: "module",
      source: `export default ${JSON.stringify(text)};`,
      shortCircuit: true,
    };
  }
  if (inStudioBase(url) && url.endsWith(".js")) {
    return {
      format: "module",
      source: fs.readFileSync(fileURLToPath(url), "utf8"),
      shortCircuit: true,
    };
  }
  return nextLoad(url, context);
}
