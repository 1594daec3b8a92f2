/* shrmkit SHRM viewer: WebGL2, plain JavaScript, no dependencies, no network.
 *
 * Page format, URL parameters and the math: data_specs/view_html.md. The page is written by
 * shrmkit.render.webgl_page; this file is package data (render/webgl/view.js) inlined there,
 * together with the GLSL files of the same folder (window.ShrmViewShaders).
 *
 *   ShrmView.mount(root, data, {hash: true|false})
 *
 * root: the element holding <canvas class="shrm-view-canvas">, <img class="shrm-view-fallback">
 * and <div class="shrm-view-ui">; data: the JSON document of the page. State is reported on
 * root.dataset: state ("loading", "ready", "fallback"), reason (why the fallback is shown),
 * frames (frames drawn so far) and view (the view drawn last, as URL parameters).
 */
(function () {
  "use strict";
  if (window.ShrmView) return;

  const DEG = Math.PI / 180;
  const MODES = ["distant", "perpixel"];
  const TONES = ["srgb", "filmic"];
  const LIMITS = {
    azimuth: [-1e6, 1e6],
    elevation: [-89, 89],
    zoom: [0.25, 10],
    exposure: [-30, 30],
    env_azimuth: [-1e6, 1e6],
    env_elevation: [-90, 90],
    env_roll: [-1e6, 1e6],
  };
  const ENV_NAMES = ["env_azimuth", "env_elevation", "env_roll"];

  // ---------------------------------------------------------------------------------------
  // decoding of the embedded arrays (little-endian, base64)
  // ---------------------------------------------------------------------------------------
  function bytesOf(b64) {
    const bin = atob(b64);
    const out = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; ++i) out[i] = bin.charCodeAt(i);
    return out;
  }

  let halfTable = null;
  function halfToFloat() {
    if (halfTable) return halfTable;
    halfTable = new Float32Array(65536);
    for (let h = 0; h < 65536; ++h) {
      const s = h & 0x8000 ? -1 : 1;
      const e = (h >> 10) & 0x1f;
      const f = h & 0x3ff;
      let v;
      if (e === 0) v = s * f * Math.pow(2, -24);
      else if (e === 31) v = f ? NaN : s * Infinity;
      else v = s * (1 + f / 1024) * Math.pow(2, e - 15);
      halfTable[h] = v;
    }
    return halfTable;
  }

  // ---------------------------------------------------------------------------------------
  // real SH (DESIGN §2 basis, flat index l² + l + m), the recurrence of render/glsl.py sh_glsl
  // (and render/webgl/shrm_sum.glsl), in double precision
  // ---------------------------------------------------------------------------------------
  function realSH(P, v) {
    const Y = new Float64Array((P + 1) * (P + 1));
    const x = v[0], y = v[1], z = v[2];
    let cm = 1, sm = 0;
    let fmm = 1 / Math.sqrt(4 * Math.PI);
    for (let m = 0; m <= P; ++m) {
      if (m > 0) {
        fmm *= -Math.sqrt((2 * m + 1) / (2 * m));
        const c = cm * x - sm * y;
        const s = cm * y + sm * x;
        cm = c;
        sm = s;
      }
      const k = m === 0 ? fmm : Math.SQRT2 * (m % 2 ? -1 : 1) * fmm;
      let h1 = 0, h2 = 0;
      for (let l = m; l <= P; ++l) {
        let h;
        if (l === m) h = 1;
        else if (l === m + 1) h = Math.sqrt(2 * m + 3) * z;
        else {
          const a = Math.sqrt((4 * l * l - 1) / (l * l - m * m));
          const b = Math.sqrt((4 * (l - 1) * (l - 1) - 1) / ((l - 1) * (l - 1) - m * m));
          h = a * (z * h1 - h2 / b);
        }
        const c0 = l * l + l;
        if (m === 0) Y[c0] = k * h;
        else {
          Y[c0 + m] = k * h * cm;
          Y[c0 - m] = k * h * sm;
        }
        h2 = h1;
        h1 = h;
      }
    }
    return Y;
  }

  // ---------------------------------------------------------------------------------------
  // camera: shrmkit.render.webgl_page.page_camera
  // ---------------------------------------------------------------------------------------
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const unit = (a) => scale(a, 1 / Math.sqrt(dot(a, a)));

  function viewDirection(view) {
    const az = view.azimuth * DEG;
    const el = view.elevation * DEG;
    return [Math.cos(el) * Math.cos(az), Math.cos(el) * Math.sin(az), Math.sin(el)];
  }

  function pageCamera(view, cam, width, height) {
    const dir = viewDirection(view);
    const forward = scale(dir, -1);
    const up0 = [0, 0, 1];
    const up = unit(sub(up0, scale(forward, dot(up0, forward))));
    const right = cross(forward, up);
    const eye = scale(dir, cam.distance);
    let tanY = Math.tan(Math.asin(cam.margin / cam.distance)) / view.zoom;
    if (width < height) tanY *= height / width;
    return { eye, forward, right, up, dir, tanY, aspect: width / height };
  }

  // the lighting rotated at view time (brdf_io/env_rotation.py): Q = Rz(AZ) Ry(-EL) Rx(ROLL);
  // returned as the column-major mat3 Q^T (its columns are the rows of Q) for uToMap
  function envRotation(view) {
    const a = (view.env_azimuth || 0) * DEG, e = (view.env_elevation || 0) * DEG, r = (view.env_roll || 0) * DEG;
    const ca = Math.cos(a), sa = Math.sin(a), ce = Math.cos(e), se = Math.sin(e), cr = Math.cos(r), sr = Math.sin(r);
    const A = [[ca * ce, -sa, -ca * se], [sa * ce, ca, -sa * se], [se, 0, ce]];  // Rz(AZ) Ry(-EL)
    // times Rx(ROLL) = [[1, 0, 0], [0, cr, -sr], [0, sr, cr]]
    const Q = A.map((row) => [row[0], row[1] * cr + row[2] * sr, -row[1] * sr + row[2] * cr]);
    return { Q, toMap: new Float32Array([].concat(Q[0], Q[1], Q[2])) };
  }
  // Q^T d: a world direction in the unrotated map's frame
  const toMapFrame = (Q, d) => [0, 1, 2].map((j) => Q[0][j] * d[0] + Q[1][j] * d[1] + Q[2][j] * d[2]);

  // column-major view-projection matrix of the camera (symmetric frustum, as vtkCamera)
  function viewProjection(c, near, far) {
    const t = c.tanY, a = c.aspect;
    const r = c.right, u = c.up, f = c.forward, e = c.eye;
    // view matrix rows: right, up, -forward; translation -rows . eye
    const V = [
      [r[0], r[1], r[2], -dot(r, e)],
      [u[0], u[1], u[2], -dot(u, e)],
      [-f[0], -f[1], -f[2], dot(f, e)],
      [0, 0, 0, 1],
    ];
    const P = [
      [1 / (a * t), 0, 0, 0],
      [0, 1 / t, 0, 0],
      [0, 0, (far + near) / (near - far), (2 * far * near) / (near - far)],
      [0, 0, -1, 0],
    ];
    const out = new Float32Array(16);
    for (let i = 0; i < 4; ++i) {
      for (let j = 0; j < 4; ++j) {
        let s = 0;
        for (let k = 0; k < 4; ++k) s += P[i][k] * V[k][j];
        out[j * 4 + i] = s;
      }
    }
    return out;
  }

  // ---------------------------------------------------------------------------------------
  // view parameters: defaults from the data, then the URL hash
  // ---------------------------------------------------------------------------------------
  function clampNumber(name, value, fallback) {
    const v = Number(value);
    if (!Number.isFinite(v)) return fallback;
    const lim = LIMITS[name];
    return lim ? Math.min(Math.max(v, lim[0]), lim[1]) : v;
  }

  function parseView(text, base) {
    const view = Object.assign({}, base);
    const params = new URLSearchParams(text.replace(/^#/, ""));
    for (const name of ["azimuth", "elevation", "zoom", "exposure", ...ENV_NAMES]) {
      if (params.has(name)) view[name] = clampNumber(name, params.get(name), view[name]);
    }
    // the environment shown, on pages with several (data.environments): an index, clamped by mount
    if (params.has("env_index") && base.env_index !== undefined) {
      const k = Math.round(Number(params.get("env_index")));
      if (Number.isFinite(k)) view.env_index = k;
    }
    if (params.has("mode") && MODES.includes(params.get("mode"))) view.mode = params.get("mode");
    if (params.has("tone") && TONES.includes(params.get("tone"))) view.tone = params.get("tone");
    if (params.has("background")) view.background = !["0", "false", "off", "black"].includes(params.get("background"));
    if (params.has("ui")) view.ui = !["0", "false", "off"].includes(params.get("ui"));
    return view;
  }

  function formatView(view) {
    const r = (x) => String(Math.round(x * 1000) / 1000);
    return (
      `azimuth=${r(view.azimuth)}&elevation=${r(view.elevation)}&zoom=${r(view.zoom)}` +
      `&exposure=${r(view.exposure)}&mode=${view.mode}&background=${view.background ? 1 : 0}&tone=${view.tone}` +
      // the lighting's rotation, when it turns
      (view.env_azimuth || view.env_elevation || view.env_roll
        ? `&env_azimuth=${r(view.env_azimuth)}&env_elevation=${r(view.env_elevation)}` +
          (view.env_roll ? `&env_roll=${r(view.env_roll)}` : "") : "") +
      (view.env_index !== undefined ? `&env_index=${view.env_index}` : "")
    );
  }

  // ---------------------------------------------------------------------------------------
  // WebGL set-up
  // ---------------------------------------------------------------------------------------
  function shaderSource(parts, defines) {
    const head = [
      "#version 300 es",
      "precision highp float;",
      "precision highp int;",
      "precision highp sampler2D;",
    ];
    for (const [k, v] of Object.entries(defines || {})) head.push(`#define ${k} ${v}`);
    return head.join("\n") + "\n" + parts.map((p) => {
      if (!(p in window.ShrmViewShaders)) throw new Error(`shader part ${p} missing`);
      return `// ---- ${p}\n` + window.ShrmViewShaders[p];
    }).join("\n");
  }

  function compile(gl, type, source, name) {
    const s = gl.createShader(type);
    gl.shaderSource(s, source);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) {
      throw new Error(`${name}: ${gl.getShaderInfoLog(s)}`);
    }
    return s;
  }

  function program(gl, vertParts, fragParts, defines, name) {
    const p = gl.createProgram();
    gl.attachShader(p, compile(gl, gl.VERTEX_SHADER, shaderSource(vertParts, defines), name + " (vertex)"));
    gl.attachShader(p, compile(gl, gl.FRAGMENT_SHADER, shaderSource(fragParts, defines), name + " (fragment)"));
    gl.bindAttribLocation(p, 0, "aPosition");
    gl.bindAttribLocation(p, 1, "aNormal");
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(`${name}: ${gl.getProgramInfoLog(p)}`);
    const uniforms = {};
    const n = gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS);
    for (let i = 0; i < n; ++i) {
      const info = gl.getActiveUniform(p, i);
      uniforms[info.name] = gl.getUniformLocation(p, info.name);
    }
    return { p, u: uniforms };
  }

  // an RGB texture read only with texelFetch (NEAREST: complete without float filtering)
  function texture(gl, width, height, internal, type, data) {
    const t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, t);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    gl.texImage2D(gl.TEXTURE_2D, 0, internal, width, height, 0, gl.RGB, type, data);
    return t;
  }

  // the constant uniforms of the lights and the BRDF (data.lights.uniforms: {name: {type, value}})
  function setUniforms(gl, o, uniforms) {
    gl.useProgram(o.p);
    for (const [name, u] of Object.entries(uniforms)) {
      const loc = o.u[name] !== undefined ? o.u[name] : o.u[name + "[0]"];
      if (loc === undefined || loc === null) continue;  // not used by this program (optimized away)
      const v = new Float32Array(u.value);
      if (u.type === "int") gl.uniform1i(loc, Math.round(u.value[0]));
      else if (u.type === "float") gl.uniform1f(loc, v[0]);
      else if (u.type === "vec3" || u.type === "vec3[]") gl.uniform3fv(loc, v);
      else throw new Error(`uniform ${name}: unknown type ${u.type}`);
    }
  }

  function halfTexels(b64, count) {
    const bytes = bytesOf(b64);
    if (bytes.length !== count * 2) throw new Error(`expected ${count * 2} bytes of half floats, got ${bytes.length}`);
    return new Uint16Array(bytes.buffer);
  }

  // ---------------------------------------------------------------------------------------
  // the viewer
  // ---------------------------------------------------------------------------------------
  function mount(root, data, options) {
    options = options || {};
    const canvas = root.querySelector(".shrm-view-canvas");
    const ui = root.querySelector(".shrm-view-ui");
    const base = Object.assign({ ui: true, env_azimuth: 0, env_elevation: 0 }, data.view);
    let view = options.hash ? parseView(window.location.hash, base) : Object.assign({}, base);
    root.dataset.state = "loading";

    function fallback(reason) {
      root.dataset.state = "fallback";
      root.dataset.reason = reason;
      const note = root.querySelector(".shrm-view-fallback-note");
      if (note) {
        const still = data.still || {};
        const v = still.view || {};
        note.textContent = still.renderer && still.renderer !== "none"
          ? `${reason}. Showing a still image instead (${still.renderer}; azimuth ${v.azimuth}°, ` +
            `elevation ${v.elevation}°, mode ${v.mode}).`
          : `${reason}.`;
      }
      return null;
    }

    // the environments the page switches between (data.environments, data_specs/view_html.md): the
    // first one's payloads are the document's own shrm, env and lights
    const ENVS = data.environments && data.environments.length > 1
      ? data.environments.map((e, k) => (k === 0 ? { name: e.name, shrm: data.shrm, env: data.env, lights: data.lights } : e))
      : [{ name: data.environment, shrm: data.shrm, env: data.env, lights: data.lights }];
    const clampIndex = (k) => Math.min(Math.max(Number.isFinite(k) ? k : 0, 0), ENVS.length - 1);
    if (view.env_index !== undefined) view.env_index = clampIndex(view.env_index);

    let gl = null;
    try {
      gl = canvas.getContext("webgl2", {
        alpha: false, antialias: false, depth: true, premultipliedAlpha: false, preserveDrawingBuffer: false,
      });
    } catch (e) {
      gl = null;
    }
    if (!gl) return fallback("WebGL2 is not available in this browser");

    let maxTex = 0;
    const shared = {};  // the mesh's buffers and the background program, for every environment
    const perEnv = [];  // per environment: its programs, textures and view-map tiles, made on first use

    function setupEnvironment(k) {
      const E = ENVS[k];
      const S = E.shrm;
      const r = {
        S, nc: (S.P + 1) * (S.P + 1), atlasW: S.cols * S.width, atlasH: S.rows * S.height, envData: E.env,
        mapTex: null, mapView: null, tiles: null,
      };
      if (Math.max(r.atlasW, r.atlasH) > maxTex) throw new Error(`the coefficient atlas ${r.atlasW}x${r.atlasH} exceeds MAX_TEXTURE_SIZE ${maxTex}`);
      const defines = { SHRM_P: S.P, SHRM_H: S.height, SHRM_W: S.width, SHRM_COLS: S.cols };
      let objectFrag = ["latlong.glsl", "tonemap.glsl", "object_prelude.glsl"];
      const lights = E.lights;
      if (lights) {
        // the lights beside the SHRM (lights.glsl after the BRDF's GLSL, render/brdf_glsl.py)
        Object.assign(defines, lights.defines, { SHRM_LIGHTS: 1 });
        objectFrag = objectFrag.concat(lights.glsl);
        const need = 2 * lights.count + 16;
        const have = gl.getParameter(gl.MAX_FRAGMENT_UNIFORM_VECTORS);
        if (have < need) throw new Error(`${lights.count} light samples need ${need} fragment uniform vectors, this WebGL2 has ${have}`);
      }
      r.distant = program(gl, ["object.vert"], objectFrag.concat(["object_distant.frag"]), defines, "distant");
      r.perpixel = program(gl, ["object.vert"], objectFrag.concat(["shrm_sum.glsl", "object_perpixel.frag"]), defines, "perpixel");
      if (lights) {
        for (const o of [r.distant, r.perpixel]) setUniforms(gl, o, lights.uniforms);
        const T = lights.table;
        if (T) {
          const tw = T.cols * T.shape[2], th = T.rows * T.shape[1];
          if (Math.max(tw, th) > maxTex) throw new Error(`the BRDF table ${tw}x${th} exceeds MAX_TEXTURE_SIZE ${maxTex}`);
          r.brdfTex = texture(gl, tw, th, gl.RGB16F, gl.HALF_FLOAT, halfTexels(T.texels, tw * th * 3));
        }
      }
      r.coefHalf = halfTexels(S.texels, r.atlasW * r.atlasH * 3);
      r.coefTex = texture(gl, r.atlasW, r.atlasH, gl.RGB16F, gl.HALF_FLOAT, r.coefHalf);
      if (E.env) {
        r.envTex = texture(gl, E.env.width, E.env.height, gl.RGB16F, gl.HALF_FLOAT,
          halfTexels(E.env.texels, E.env.width * E.env.height * 3));
      }
      const err = gl.getError();
      if (err !== gl.NO_ERROR) throw new Error(`WebGL error 0x${err.toString(16)} during set-up of ${E.name}`);
      return r;
    }
    function environment(k) {
      if (!perEnv[k]) perEnv[k] = setupEnvironment(k);
      return perEnv[k];
    }

    try {
      maxTex = gl.getParameter(gl.MAX_TEXTURE_SIZE);
      shared.background = ENVS.some((E) => E.env)
        ? program(gl, ["background.vert"], ["latlong.glsl", "tonemap.glsl", "background.frag"], {}, "background")
        : null;
      // mesh
      const M = data.mesh;
      const pos = new Float32Array(bytesOf(M.positions).buffer);
      const nrm = new Float32Array(bytesOf(M.normals).buffer);
      const idxBytes = bytesOf(M.indices);
      const idx = M.index_type === "uint16" ? new Uint16Array(idxBytes.buffer) : new Uint32Array(idxBytes.buffer);
      if (pos.length !== M.vertices * 3 || nrm.length !== M.vertices * 3 || idx.length !== M.triangles * 3) {
        throw new Error("mesh arrays do not match their counts");
      }
      shared.vao = gl.createVertexArray();
      gl.bindVertexArray(shared.vao);
      const vb = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, vb);
      gl.bufferData(gl.ARRAY_BUFFER, pos, gl.STATIC_DRAW);
      gl.enableVertexAttribArray(0);
      gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
      const nb = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, nb);
      gl.bufferData(gl.ARRAY_BUFFER, nrm, gl.STATIC_DRAW);
      gl.enableVertexAttribArray(1);
      gl.vertexAttribPointer(1, 3, gl.FLOAT, false, 0, 0);
      const ib = gl.createBuffer();
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, ib);
      gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, idx, gl.STATIC_DRAW);
      gl.bindVertexArray(null);
      shared.indexType = M.index_type === "uint16" ? gl.UNSIGNED_SHORT : gl.UNSIGNED_INT;
      shared.count = idx.length;
      shared.emptyVao = gl.createVertexArray();
      const err = gl.getError();
      if (err !== gl.NO_ERROR) throw new Error(`WebGL error 0x${err.toString(16)} during set-up`);
      environment(view.env_index || 0);
    } catch (e) {
      return fallback(`WebGL2 set-up failed: ${e.message}`);
    }

    // distant mode: the view map max(sum_c Y^r_c(V~) B~_c, 0) on the CPU (render/shader.py
    // distant_update), float32, once per view direction and environment
    function viewMap(r, dir) {
      const S = r.S, H = S.height, W = S.width, n = H * W * 3;
      if (!r.tiles) {
        const table = halfToFloat();
        const inv = 1 / S.scale;
        r.tiles = [];
        for (let c = 0; c < r.nc; ++c) {
          const tile = new Float32Array(n);
          const ox = (c % S.cols) * W, oy = Math.floor(c / S.cols) * H;
          for (let y = 0; y < H; ++y) {
            let src = ((oy + y) * r.atlasW + ox) * 3;
            let dst = y * W * 3;
            for (let x = 0; x < W * 3; ++x) tile[dst++] = table[r.coefHalf[src++]] * inv;
          }
          r.tiles.push(tile);
        }
      }
      const Y = realSH(S.P, dir);
      const out = new Float32Array(n);
      for (let c = 0; c < r.nc; ++c) {
        const y = Y[c], tile = r.tiles[c];
        if (y === 0) continue;
        for (let t = 0; t < n; ++t) out[t] += y * tile[t];
      }
      for (let t = 0; t < n; ++t) if (!(out[t] > 0)) out[t] = 0;
      return out;
    }

    function uploadViewMap(r, dir) {
      const key = dir.join(",");
      if (r.mapView === key) return;
      const map = viewMap(r, dir);
      if (!r.mapTex) r.mapTex = texture(gl, r.S.width, r.S.height, gl.RGB32F, gl.FLOAT, map);
      else {
        gl.bindTexture(gl.TEXTURE_2D, r.mapTex);
        gl.texSubImage2D(gl.TEXTURE_2D, 0, 0, 0, r.S.width, r.S.height, gl.RGB, gl.FLOAT, map);
      }
      r.mapView = key;
    }

    let frames = 0;
    let pending = false;
    const title = root.querySelector(".shrm-view-title");
    function draw() {
      pending = false;
      const dpr = window.devicePixelRatio || 1;
      const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
      const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
      if (canvas.width !== w || canvas.height !== h) {
        canvas.width = w;
        canvas.height = h;
      }
      gl.viewport(0, 0, w, h);
      const cam = pageCamera(view, data.camera, w, h);
      const env = envRotation(view);
      const tone = TONES.indexOf(view.tone);
      let R;
      try {
        R = environment(view.env_index || 0);
      } catch (e) {
        fallback(`WebGL2 set-up failed: ${e.message}`);
        return;
      }
      gl.disable(gl.BLEND);
      gl.clearColor(0, 0, 0, 1);
      gl.clearDepth(1);
      gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
      if (view.background && shared.background && R.envTex) {
        const b = shared.background;
        gl.useProgram(b.p);
        gl.disable(gl.DEPTH_TEST);
        gl.depthMask(false);
        gl.activeTexture(gl.TEXTURE0);
        gl.bindTexture(gl.TEXTURE_2D, R.envTex);
        gl.uniform1i(b.u.uEnv, 0);
        gl.uniform1f(b.u.uEnvScale, R.envData.scale);
        gl.uniformMatrix3fv(b.u.uToMap, false, env.toMap);
        gl.uniform3fv(b.u.uForward, cam.forward);
        gl.uniform3fv(b.u.uRight, cam.right);
        gl.uniform3fv(b.u.uUp, cam.up);
        gl.uniform1f(b.u.uTanY, cam.tanY);
        gl.uniform2f(b.u.uSize, w, h);
        gl.uniform1f(b.u.uExposure, view.exposure);
        gl.uniform1i(b.u.uTone, tone);
        gl.bindVertexArray(shared.emptyVao);
        gl.drawArrays(gl.TRIANGLES, 0, 3);
        gl.depthMask(true);
      }
      const o = view.mode === "perpixel" ? R.perpixel : R.distant;
      gl.useProgram(o.p);
      gl.enable(gl.DEPTH_TEST);
      gl.depthFunc(gl.LESS);
      if (R.brdfTex) {
        // a measured BRDF's table (brdf_table.glsl) on texture unit 1
        gl.activeTexture(gl.TEXTURE1);
        gl.bindTexture(gl.TEXTURE_2D, R.brdfTex);
        gl.uniform1i(o.u.shrmBrdfTex, 1);
      }
      gl.activeTexture(gl.TEXTURE0);
      if (view.mode === "perpixel") {
        gl.bindTexture(gl.TEXTURE_2D, R.coefTex);
        gl.uniform1i(o.u.uCoef, 0);
        gl.uniform1f(o.u.uScale, R.S.scale);
      } else {
        // V~: from the mesh's bounding-box centre toward the eye (camera.view_direction), in the
        // unrotated map's frame (Q^T V~), as render/vtk_renderer.py update_view_maps
        uploadViewMap(R, toMapFrame(env.Q, unit(sub(cam.eye, data.mesh.center))));
        gl.bindTexture(gl.TEXTURE_2D, R.mapTex);
        gl.uniform1i(o.u.uMap, 0);
      }
      const near = Math.max(1e-3, data.camera.distance - 2), far = data.camera.distance + 2;
      gl.uniformMatrix4fv(o.u.uViewProj, false, viewProjection(cam, near, far));
      gl.uniform3fv(o.u.uEye, cam.eye);
      gl.uniformMatrix3fv(o.u.uToMap, false, env.toMap);
      gl.uniform1f(o.u.uExposure, view.exposure);
      gl.uniform1i(o.u.uTone, tone);
      gl.bindVertexArray(shared.vao);
      gl.drawElements(gl.TRIANGLES, shared.count, shared.indexType, 0);
      gl.bindVertexArray(null);
      frames += 1;
      root.dataset.frames = String(frames);
      root.dataset.view = formatView(view);
      root.dataset.environment = ENVS[view.env_index || 0].name;
      if (ENVS.length > 1 && title) title.textContent = `${data.brdf} under ${ENVS[view.env_index || 0].name}`;
      root.dataset.state = "ready";
      const glErr = gl.getError();
      if (glErr !== gl.NO_ERROR) root.dataset.glError = `0x${glErr.toString(16)}`;
      syncControls();
    }

    function redraw() {
      if (!pending) {
        pending = true;
        window.requestAnimationFrame(draw);
      }
    }

    function storeHash() {
      if (options.hash && window.history && window.history.replaceState) {
        try {
          window.history.replaceState(null, "", "#" + formatView(view) + (view.ui ? "" : "&ui=0"));
        } catch (e) {
          /* some file:// contexts refuse replaceState; the view still works */
        }
      }
    }

    // ---- controls (built here so that a page without JavaScript shows none)
    const controls = {};
    function syncControls() {
      if (!controls.exposure) return;
      controls.exposure.value = String(view.exposure);
      controls.exposureText.textContent = `${view.exposure >= 0 ? "+" : ""}${view.exposure.toFixed(1)} EV`;
      controls.background.checked = !!view.background;
      controls.mode.value = view.mode;
      controls.lighting.value = String(((view.env_azimuth % 360) + 540) % 360 - 180);
      if (controls.environment) controls.environment.value = String(view.env_index || 0);
      root.classList.toggle("shrm-view-noui", !view.ui);
    }

    function buildControls() {
      if (!ui) return;
      const el = (tag, attrs, text) => {
        const e = document.createElement(tag);
        for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
        if (text !== undefined) e.textContent = text;
        return e;
      };
      const bar = el("div", { class: "shrm-view-controls" });
      const expLabel = el("label", {}, "exposure ");
      controls.exposure = el("input", { type: "range", min: "-12", max: "12", step: "0.1", "aria-label": "exposure" });
      controls.exposureText = el("span", { class: "shrm-view-ev" });
      expLabel.append(controls.exposure, controls.exposureText);
      const bgLabel = el("label", {});
      controls.background = el("input", { type: "checkbox" });
      bgLabel.append(controls.background, document.createTextNode(" environment"));
      if (!shared.background) controls.background.disabled = true;
      const modeLabel = el("label", {}, "mode ");
      controls.mode = el("select", { "aria-label": "render mode" });
      for (const m of MODES) controls.mode.append(el("option", { value: m }, m));
      modeLabel.append(controls.mode);
      const lightLabel = el("label", { title: "turn the environment about the up axis (Shift+drag: also tilt it)" },
        "lighting ");
      controls.lighting = el("input", { type: "range", min: "-180", max: "180", step: "1",
        "aria-label": "lighting azimuth" });
      lightLabel.append(controls.lighting);
      const reset = el("button", { type: "button" }, "reset view");
      bar.append(expLabel, bgLabel, modeLabel, lightLabel);
      if (ENVS.length > 1) {
        // several environments (shrm view --env A B ...): switched here, without reloading
        const envLabel = el("label", {}, "environment ");
        controls.environment = el("select", { "aria-label": "environment" });
        ENVS.forEach((E, k) => controls.environment.append(el("option", { value: String(k) }, E.name)));
        envLabel.append(controls.environment);
        bar.append(envLabel);
        controls.environment.addEventListener("change", () => {
          view.env_index = clampIndex(Math.round(Number(controls.environment.value)));
          redraw();
          storeHash();
        });
      }
      bar.append(reset);
      ui.append(bar);
      controls.exposure.addEventListener("input", () => {
        view.exposure = clampNumber("exposure", controls.exposure.value, view.exposure);
        redraw();
      });
      controls.exposure.addEventListener("change", storeHash);
      controls.lighting.addEventListener("input", () => {
        view.env_azimuth = clampNumber("env_azimuth", controls.lighting.value, view.env_azimuth);
        redraw();
      });
      controls.lighting.addEventListener("change", storeHash);
      controls.background.addEventListener("change", () => {
        view.background = controls.background.checked;
        redraw();
        storeHash();
      });
      controls.mode.addEventListener("change", () => {
        if (MODES.includes(controls.mode.value)) view.mode = controls.mode.value;
        redraw();
        storeHash();
      });
      reset.addEventListener("click", () => {
        view = Object.assign({}, base, { ui: view.ui });
        redraw();
        storeHash();
      });
    }

    // ---- orbit (drag), the lighting (Shift+drag) and zoom (wheel)
    let drag = null;
    canvas.addEventListener("pointerdown", (e) => {
      drag = { x: e.clientX, y: e.clientY, env: e.shiftKey };
      try { canvas.setPointerCapture(e.pointerId); } catch (err) { /* not capturable */ }
    });
    canvas.addEventListener("pointermove", (e) => {
      if (!drag) return;
      if (drag.env) {  // Shift+drag turns the environment (and the lights in it), not the camera
        view.env_azimuth += 0.4 * (e.clientX - drag.x);
        view.env_elevation = clampNumber("env_elevation", view.env_elevation - 0.4 * (e.clientY - drag.y),
          view.env_elevation);
      } else {
        view.azimuth -= 0.4 * (e.clientX - drag.x);
        view.elevation = clampNumber("elevation", view.elevation + 0.4 * (e.clientY - drag.y), view.elevation);
      }
      drag = { x: e.clientX, y: e.clientY, env: drag.env };
      redraw();
    });
    const endDrag = () => {
      if (drag) storeHash();
      drag = null;
    };
    canvas.addEventListener("pointerup", endDrag);
    canvas.addEventListener("pointercancel", endDrag);
    canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      view.zoom = clampNumber("zoom", view.zoom * Math.exp(-0.0015 * e.deltaY), view.zoom);
      redraw();
      storeHash();
    }, { passive: false });
    canvas.addEventListener("dblclick", () => {
      view = Object.assign({}, base, { ui: view.ui });
      redraw();
      storeHash();
    });
    if (options.hash) {
      window.addEventListener("hashchange", () => {
        view = parseView(window.location.hash, base);
        if (view.env_index !== undefined) view.env_index = clampIndex(view.env_index);
        redraw();
      });
    }
    window.addEventListener("resize", redraw);
    // the canvas may be hidden (0 × 0) when the first frame is drawn — e.g. until the
    // fallback image is swapped out — so redraw whenever its laid-out size changes
    if (typeof ResizeObserver === "function") new ResizeObserver(redraw).observe(canvas);
    canvas.addEventListener("webglcontextlost", (e) => {
      e.preventDefault();
      fallback("the WebGL2 context was lost");
    });

    // the info bar: a click folds the notes and the help away (and back)
    const info = root.querySelector(".shrm-view-info");
    if (info) {
      info.title = "click to fold or unfold the details";
      info.addEventListener("click", () => root.classList.toggle("shrm-view-folded"));
    }
    buildControls();
    syncControls();
    draw();
    return { redraw, get view() { return Object.assign({}, view); } };
  }

  window.ShrmView = { mount, realSH, pageCamera, parseView, formatView };
})();
