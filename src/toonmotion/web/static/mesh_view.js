// The stage: the textured mesh drawn with WebGL 2 from the vertices the server sends, and a 2D
// overlay for handles (joints, bones). Coordinates: drawing pixels (x right, y down) are mapped
// to the canvas by a uniform scale and offset that fit the drawing with a margin.

const VERTEX_SHADER = `#version 300 es
in vec2 a_position;   // deformed vertex, drawing pixels
in vec2 a_texcoord;   // rest vertex / drawing size
uniform vec4 u_view;  // scale x, scale y, offset x, offset y: drawing pixels -> clip space
out vec2 v_texcoord;
void main() {
  gl_Position = vec4(a_position * u_view.xy + u_view.zw, 0.0, 1.0);
  v_texcoord = a_texcoord;
}`;

const FRAGMENT_SHADER = `#version 300 es
precision mediump float;
in vec2 v_texcoord;
uniform sampler2D u_texture;
out vec4 colour;
void main() { colour = texture(u_texture, v_texcoord); }`;

const MARGIN = 0.12; // of the drawing's size, around it

export class MeshView {
  constructor(meshCanvas, overlayCanvas, project, image) {
    this.canvas = meshCanvas;
    this.overlay = overlayCanvas;
    this.project = project;
    this.rest = new Float32Array(project.vertices);
    this.vertices = new Float32Array(project.vertices);
    /** @type {(pen: CanvasRenderingContext2D) => void} what the panel draws over the drawing */
    this.drawOverlay = () => {};
    const gl = meshCanvas.getContext("webgl2", { premultipliedAlpha: true, alpha: true, preserveDrawingBuffer: true });
    if (!gl) throw new Error("this browser has no WebGL 2, which the editor needs to draw the drawing");
    this.gl = gl;
    this.program = program(gl, VERTEX_SHADER, FRAGMENT_SHADER);
    const texcoords = new Float32Array(this.rest.length);
    for (let i = 0; i < this.rest.length; i += 2) {
      texcoords[i] = (this.rest[i] + 0.5) / project.width;
      texcoords[i + 1] = (this.rest[i + 1] + 0.5) / project.height;
    }
    this.positionBuffer = buffer(gl, gl.ARRAY_BUFFER, this.vertices, gl.DYNAMIC_DRAW);
    this.texcoordBuffer = buffer(gl, gl.ARRAY_BUFFER, texcoords, gl.STATIC_DRAW);
    this.indexBuffer = buffer(gl, gl.ELEMENT_ARRAY_BUFFER, new Uint32Array(project.triangles), gl.STATIC_DRAW);
    this.count = project.triangles.length;
    this.texture = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, this.texture);
    gl.pixelStorei(gl.UNPACK_PREMULTIPLY_ALPHA_WEBGL, true);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, gl.RGBA, gl.UNSIGNED_BYTE, image);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    new ResizeObserver(() => this.resize()).observe(meshCanvas);
    this.resize();
  }

  // Fit the drawing (plus margin) in the canvas; keep both canvases at device resolution.
  resize() {
    const ratio = window.devicePixelRatio || 1;
    for (const c of [this.canvas, this.overlay]) {
      c.width = Math.max(1, Math.round(c.clientWidth * ratio));
      c.height = Math.max(1, Math.round(c.clientHeight * ratio));
    }
    const { width, height } = this.project;
    const span = [width * (1 + 2 * MARGIN), height * (1 + 2 * MARGIN)];
    this.scale = Math.min(this.canvas.width / span[0], this.canvas.height / span[1]);
    this.offset = [(this.canvas.width - width * this.scale) / 2, (this.canvas.height - height * this.scale) / 2];
    this.draw();
  }

  toCanvas([x, y]) {
    return [x * this.scale + this.offset[0], y * this.scale + this.offset[1]];
  }

  // A pointer event's position in drawing pixels.
  toDrawing(event) {
    const box = this.overlay.getBoundingClientRect();
    const ratio = this.overlay.width / box.width;
    return [((event.clientX - box.left) * ratio - this.offset[0]) / this.scale,
            ((event.clientY - box.top) * ratio - this.offset[1]) / this.scale];
  }

  // The triangles in draw order (back to front), after a depth change.
  setTriangles(flat) {
    const gl = this.gl;
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.indexBuffer);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, new Uint32Array(flat), gl.STATIC_DRAW);
    this.count = flat.length;
    this.draw();
  }

  setVertices(flat) {
    this.vertices = new Float32Array(flat);
    this.draw();
  }

  /** Draws the deformed vertices of a reply's "U": base64 of little-endian float32 x0, y0, ...
   * (toonmotion.web.wire), which a typed array reads as they are on every browser's platform. */
  showDeformed(encoded) {
    const bytes = Uint8Array.from(atob(encoded), (c) => c.charCodeAt(0));
    this.vertices = new Float32Array(bytes.buffer);
    this.draw();
  }

  draw() {
    const gl = this.gl;
    gl.viewport(0, 0, this.canvas.width, this.canvas.height);
    gl.clearColor(0, 0, 0, 0);
    gl.clear(gl.COLOR_BUFFER_BIT);
    gl.useProgram(this.program);
    gl.enable(gl.BLEND);
    gl.blendFunc(gl.ONE, gl.ONE_MINUS_SRC_ALPHA);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.positionBuffer);
    gl.bufferData(gl.ARRAY_BUFFER, this.vertices, gl.DYNAMIC_DRAW);
    attribute(gl, this.program, "a_position", this.positionBuffer);
    attribute(gl, this.program, "a_texcoord", this.texcoordBuffer);
    // drawing pixels -> canvas pixels -> clip space (y up)
    const sx = (2 * this.scale) / this.canvas.width, sy = (-2 * this.scale) / this.canvas.height;
    gl.uniform4f(gl.getUniformLocation(this.program, "u_view"), sx, sy,
                 (2 * this.offset[0]) / this.canvas.width - 1, 1 - (2 * this.offset[1]) / this.canvas.height);
    gl.bindTexture(gl.TEXTURE_2D, this.texture);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.indexBuffer);
    gl.drawElements(gl.TRIANGLES, this.count, gl.UNSIGNED_INT, 0);
    const pen = this.overlay.getContext("2d");
    pen.clearRect(0, 0, this.overlay.width, this.overlay.height);
    this.drawOverlay(pen);
  }
}

function shader(gl, kind, source) {
  const s = gl.createShader(kind);
  gl.shaderSource(s, source);
  gl.compileShader(s);
  if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(`shader: ${gl.getShaderInfoLog(s)}`);
  return s;
}

function program(gl, vertexSource, fragmentSource) {
  const p = gl.createProgram();
  gl.attachShader(p, shader(gl, gl.VERTEX_SHADER, vertexSource));
  gl.attachShader(p, shader(gl, gl.FRAGMENT_SHADER, fragmentSource));
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(`program: ${gl.getProgramInfoLog(p)}`);
  return p;
}

function buffer(gl, target, data, usage) {
  const b = gl.createBuffer();
  gl.bindBuffer(target, b);
  gl.bufferData(target, data, usage);
  return b;
}

function attribute(gl, prog, name, buf) {
  const at = gl.getAttribLocation(prog, name);
  gl.bindBuffer(gl.ARRAY_BUFFER, buf);
  gl.enableVertexAttribArray(at);
  gl.vertexAttribPointer(at, 2, gl.FLOAT, false, 0, 0);
}
