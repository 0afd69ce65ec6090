// ESLint for the TypeScript library and tests (type-aware: the rules that
// find unawaited or misused promises need the types) and for the CommonJS
// files Node loads as they are: the Node-RED nodes, bin/, demo/, bench/ and
// the JS tests and helpers. The scripts inside nodes/*.html run in the
// editor's browser and are not linted here. Layout is prettier's job.
// `npm run lint` runs this and `prettier --check`; test/lint.test.ts runs
// both inside `npm test`.
import js from '@eslint/js';
import { defineConfig } from 'eslint/config';
import globals from 'globals';
import tseslint from 'typescript-eslint';

/** Bug-finding rules beyond `recommended`, for every file. */
const extraRules = {
  eqeqeq: ['error', 'always', { null: 'ignore' }],
  'no-var': 'error',
  'prefer-const': ['error', { destructuring: 'all' }],
  'no-throw-literal': 'error',
  'no-self-compare': 'error',
  'no-template-curly-in-string': 'error',
  'no-unmodified-loop-condition': 'error',
  'no-unreachable-loop': 'error',
};

/** A leading underscore marks a binding kept on purpose (a callback's fixed signature, a skipped element). */
const unusedVars = {
  args: 'after-used',
  argsIgnorePattern: '^_',
  varsIgnorePattern: '^_',
  caughtErrors: 'all',
  caughtErrorsIgnorePattern: '^_',
  destructuredArrayIgnorePattern: '^_',
  ignoreRestSiblings: true,
};

export default defineConfig(
  {
    ignores: ['dist/**', 'docs/api/**', '**/node_modules/**', 'test/nr5/**', 'examples/**', 'coverage/**'],
  },
  {
    linterOptions: { reportUnusedDisableDirectives: 'error' },
  },
  {
    files: ['lib/**/*.ts', 'test/**/*.ts'],
    extends: [js.configs.recommended, ...tseslint.configs.recommendedTypeChecked],
    languageOptions: {
      parserOptions: { projectService: true, tsconfigRootDir: import.meta.dirname },
      globals: { ...globals.node, ...globals.mocha },
    },
    rules: {
      ...extraRules,
      '@typescript-eslint/no-unused-vars': ['error', unusedVars],
      // `arr[i]!` is written throughout as if noUncheckedIndexedAccess were on: the `!` records that the
      // index was checked. Without that compiler option every one of them counts as "unnecessary".
      '@typescript-eslint/no-unnecessary-type-assertion': 'off',
      // Codecs compare bytes off the wire (numbers) with the protocol's const enums; that is decoding.
      '@typescript-eslint/no-unsafe-enum-comparison': 'off',
      // `async` without `await` is deliberate: a synchronous throw becomes a rejection, and the
      // signature matches the async interface it implements (open(), close()).
      '@typescript-eslint/require-await': 'off',
      // Fires on every function-valued member written in method syntax (Entry.resolve, CODECS[type].decode,
      // PendingRequests.prototype.add for captureStackTrace); none of those passed around uses `this`.
      '@typescript-eslint/unbound-method': 'off',
      // `const client = this` names the owner inside object literals whose methods have their own `this`.
      '@typescript-eslint/no-this-alias': 'off',
      // Forwarding a caught value (`catch (err) { reject(err) }`, an abort signal's reason) is not
      // inventing a non-Error reason.
      '@typescript-eslint/prefer-promise-reject-errors': ['error', { allowThrowingAny: true, allowThrowingUnknown: true }],
      // `for (const w of waiters) (err ? w.reject(err) : w.resolve());` is a statement, not a lost value.
      '@typescript-eslint/no-unused-expressions': ['error', { allowTernary: true }],
    },
  },
  {
    // Tests drive untyped parts: Node-RED's runtime and test helper, flows parsed from JSON, the
    // CommonJS node files (required, not imported, as Node-RED loads them). The library keeps these on.
    files: ['test/**/*.ts'],
    rules: {
      '@typescript-eslint/no-explicit-any': 'off',
      '@typescript-eslint/no-unsafe-argument': 'off',
      '@typescript-eslint/no-unsafe-assignment': 'off',
      '@typescript-eslint/no-unsafe-call': 'off',
      '@typescript-eslint/no-unsafe-member-access': 'off',
      '@typescript-eslint/no-unsafe-return': 'off',
      '@typescript-eslint/no-require-imports': 'off',
      // chai's property assertions: `expect(x).to.be.true`.
      '@typescript-eslint/no-unused-expressions': 'off',
      // Assertion messages show whatever is being checked, arrays and `{}` included.
      '@typescript-eslint/restrict-template-expressions': 'off',
      '@typescript-eslint/no-base-to-string': 'off',
    },
  },
  {
    files: ['bench/**/*.js', 'nodes/**/*.js', 'demo/*.js', 'bin/*.js', 'test/**/*.js'],
    extends: [js.configs.recommended],
    languageOptions: {
      ecmaVersion: 2022,
      sourceType: 'commonjs',
      globals: { ...globals.node },
    },
    rules: {
      ...extraRules,
      'no-unused-vars': ['error', unusedVars],
    },
  },
  {
    files: ['test/**/*.js'],
    languageOptions: { globals: { ...globals.mocha } },
  },
);
