// ESLint for the editor's page (src/toonmotion/web/static): the recommended rules, in a browser,
// as ES modules. `make test` runs it (0 problems); TypeScript's checker runs beside it (tsconfig.json).
import js from "@eslint/js";
import globals from "globals";

export default [
  js.configs.recommended,
  {
    files: ["src/toonmotion/web/static/*.js"],
    languageOptions: { ecmaVersion: 2022, sourceType: "module", globals: { ...globals.browser } },
  },
];
