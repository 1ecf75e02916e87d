// Hapticd.Client: one session with a hapticd server, in managed code alone (no native library):
// the control plane over hapticd's HTTP face (protobuf JSON, docs/http.md), the state stream over
// UDP with the C++ SDK's datagrams and SipHash tag (docs/protocol.md), the events over WebSocket.
// Objects and fields come back as handles (IDisposable: Dispose removes the item); state arrives
// by callback (on the client's receive thread) or by polling; a refused call throws
// HapticException with the code and the "call: field: problem" message, and changes nothing.
//
//   using (var client = new Hapticd.Client(new Hapticd.ClientConfig { ServerAddress = "host:8081" }))
//   {
//       var wall = Hapticd.WallSpec.Default;
//       wall.Impedance = new Hapticd.Impedance(1000, 1);
//       using (var handle = client.AddWall(wall)) { ... client.PollState(out state, 100) ... }
//   }
using System;
using System.Collections.Generic;
using System.IO;
using System.Net;
using System.Net.Sockets;
using System.Security.Cryptography.X509Certificates;
using System.Text;
using System.Threading;

namespace Hapticd
{
    /// <summary>How to reach hapticd; the defaults are the C++ SDK's, but for the address: the
    /// HTTP face's (hapticd --http-api PORT, or http_address in its configuration).</summary>
    public sealed class ClientConfig
    {
        /// <summary>host:port of hapticd's HTTP face ("[::1]:8081" for IPv6). An https:// prefix
        /// asks for TLS as TlsCaFile does (trusting the system's CAs without one).</summary>
        public string ServerAddress = "127.0.0.1:8081";
        public string ClientName = "haptic-client";
        public string Token = "";
        public string TlsCaFile = "";    // non-empty: TLS, the server's certificate signed by this CA (PEM)
        /// <summary>Mutual TLS: the client's certificate with its private key as PKCS#12
        /// (.p12/.pfx; openssl pkcs12 -export makes one from PEM files). A PEM certificate with a
        /// TlsKeyFile is refused, saying so: .NET Standard 2.1 reads no PEM keys.</summary>
        public string TlsCertFile = "";
        public string TlsKeyFile = "";
        public string TlsCertPassword = "";  // of TlsCertFile's PKCS#12; empty: none
        public string TlsServerName = "";    // the name the server's certificate carries; default: the host
        public string UdpAddress = "";       // host:port to send datagrams to instead of the server's
        public uint RpcTimeoutMs = 2000;
        public uint HeartbeatPeriodMs = 100;
        public uint StateDecimation = 1;     // state every n-th tick; 0: none
        public uint DeviceIndex;
        public bool Reconnect = true;
        public bool AllowPlaintextToken;
        public bool LockstepFlowControl = true;
        public uint ReconnectBackoffMinMs = 50;
        public uint ReconnectBackoffMaxMs = 1000;
    }

    /// <summary>What ObjectHandle and FieldHandle share: one item of the client's. Dispose (or
    /// Remove) removes it from the server; a handle only collected lets go of it (the item stays
    /// until the session ends). A handle from before an ApplyScene or Reset is stale: it removes
    /// nothing.</summary>
    public abstract class ItemHandle : IDisposable
    {
        internal readonly Client Owner;
        internal ulong Key;
        internal readonly ulong Generation;
        internal StabilityReport StabilityReport_;
        internal ItemHandle(Client owner, ulong key, ulong generation, StabilityReport stability)
        {
            Owner = owner;
            Key = key;
            Generation = generation;
            StabilityReport_ = stability;
        }

        internal abstract bool IsObject { get; }

        internal ulong Live(string call)
        {
            if (Key == 0) throw new HapticException(ErrorCode.FailedPrecondition, call + ": handle: removed or released already");
            return Key;
        }

        /// <summary>The item's id on the server now (it changes when a reconnection registers it
        /// on a restarted server); 0 once removed or released.</summary>
        public ulong Id { get { return Key == 0 ? 0 : Owner.ServerIdOf(Key, Generation); } }
        public bool Owned { get { return Key != 0; } }

        /// <summary>The server's stability report for the impedance as registered or last updated.</summary>
        public StabilityReport Stability { get { Live("stability"); return StabilityReport_; } }

        /// <summary>Removes the item now; its force ramps out on the server.</summary>
        public void Remove()
        {
            if (Key == 0) return;
            var key = Key;
            Key = 0;
            Owner.Remove(key, Generation, IsObject);
        }

        /// <summary>Stops owning the item (it stays until the session ends); returns its id.</summary>
        public ulong Release()
        {
            if (Key == 0) return 0;
            var id = Owner.ServerIdOf(Key, Generation);
            Owner.Forget(Key);
            Key = 0;
            return id;
        }

        public void Dispose() { Remove(); }
    }

    /// <summary>A registered object of any kind.</summary>
    public sealed class ObjectHandle : ItemHandle
    {
        internal ObjectHandle(Client owner, ulong key, ulong generation, StabilityReport stability) : base(owner, key, generation, stability) { }
        internal override bool IsObject { get { return true; } }

        private void Replace(object spec) { StabilityReport_ = Owner.UpdateItem(this, spec); }
        public void Update(WallSpec s) { Replace(s); }
        public void Update(SphereSpec s) { Replace(s); }
        public void Update(BoxSpec s) { Replace(s); }
        public void Update(CapsuleSpec s) { Replace(s); }
        public void Update(TangentPlaneSpec s) { Replace(s); }
        public void Update(MeshSpec mesh) { Replace(mesh); }
    }

    /// <summary>A registered field of any kind.</summary>
    public sealed class FieldHandle : ItemHandle
    {
        internal FieldHandle(Client owner, ulong key, ulong generation, StabilityReport stability) : base(owner, key, generation, stability) { }
        internal override bool IsObject { get { return false; } }

        private void Replace(object spec) { StabilityReport_ = Owner.UpdateItem(this, spec); }
        public void Update(SpringFieldSpec s) { Replace(s); }
        public void Update(DistanceSpringSpec s) { Replace(s); }
        public void Update(PotentialFieldSpec s) { Replace(s); }
        public void Update(LinearFieldSpec s) { Replace(s); }
        public void Update(ViscousFieldSpec s) { Replace(s); }
        public void Update(DetentFieldSpec s) { Replace(s); }
        public void Update(OrientationSpringSpec s) { Replace(s); }
        public void Update(OrientationDetentSpec s) { Replace(s); }
    }

    /// <summary>The handles of a scene applied whole, each list in the scene's order.</summary>
    public sealed class AppliedScene
    {
        public List<ObjectHandle> Objects = new List<ObjectHandle>();
        public List<FieldHandle> Fields = new List<FieldHandle>();
        /// <summary>One per object, in order.</summary>
        public List<StabilityReport> Stability = new List<StabilityReport>();
    }

    /// <summary>The server's scene as read back: specs (WallSpec, MeshSpec, ...) with their ids
    /// and sessions, in the server's order.</summary>
    public sealed class RegisteredScene
    {
        public List<object> Objects = new List<object>();
        public List<object> Fields = new List<object>();
        public List<ulong> ObjectIds = new List<ulong>();
        public List<ulong> FieldIds = new List<ulong>();
        public List<ulong> ObjectSessions = new List<ulong>();
        public List<ulong> FieldSessions = new List<ulong>();
    }

    public sealed class Client : IDisposable
    {
        /// <summary>The haptic.v1 API version this client speaks (OpenSessionRequest.api_version).</summary>
        public const uint ApiVersion = 5;

        private readonly ClientConfig config_;
        private readonly Endpoint endpoint_;
        private readonly HttpChannel channel_;
        private readonly string token_;
        private readonly object identity_ = new object();
        private ulong sessionId_;           // guarded by identity_
        private string sessionSecret_ = ""; // guarded by identity_: base64, as OpenSession gave it
        private DeviceInfo deviceInfo_;
        private long leaseTimeoutMs_;
        private StateLink link_;
        private bool closed_;
        private uint decimation_;
        private ulong knownRun_;
        private readonly object runGate_ = new object();

        // Items by the client's own key (stable across reconnections), in the order made.
        private sealed class Item
        {
            internal bool IsObject;
            internal JsonObject Message;
            internal ulong ServerId;      // 0: a reconnection could not register it again
            internal string LostReason = "";
        }
        private readonly object itemsGate_ = new object();
        private readonly SortedDictionary<ulong, Item> items_ = new SortedDictionary<ulong, Item>();
        private ulong nextKey_ = 1;        // guarded by itemsGate_
        private long generation_;          // bumped by ApplyScene and Reset: older handles go stale

        private Action<State> onState_;
        private Action<Event> onEvent_;
        private Action<ConnectionChange> onConnection_;
        private readonly object eventsGate_ = new object();
        private EventWatch events_;        // guarded by eventsGate_
        private long callbackExceptions_;
        private readonly List<Recorder> recorders_ = new List<Recorder>();  // open ones, for connection changes

        private int connectionState_ = (int)ConnectionState.Connected;
        private volatile bool heartbeatsEnabled_ = true;
        private Thread supervisor_;
        private readonly ManualResetEvent stopSupervisor_ = new ManualResetEvent(false);

        /// <summary>Connects and opens a session. Throws HapticException (Connection,
        /// VersionMismatch, InvalidArgument naming the field, ...).</summary>
        public Client(ClientConfig config)
        {
            if (config == null) throw new HapticException(ErrorCode.InvalidArgument, "ClientConfig: config: is null");
            config_ = config;
            endpoint_ = EndpointOf(config);
            token_ = config.Token ?? "";
            CheckConfig(config, endpoint_);
            channel_ = new HttpChannel(endpoint_);
            var opened = OpenSession();
            try
            {
                link_ = new StateLink(UdpEndpoint(opened.U32("udp_port")), opened.U64("session_id"), KeyOf(opened),
                                      (int)config.HeartbeatPeriodMs);
                link_.HeartbeatsEnabled = true;
                if (config.StateDecimation > 0) Subscribe(config.StateDecimation);
            }
            catch
            {
                // Do not leave a half-open session holding a lease; report the first failure.
                try { CloseSession(); } catch (HapticException) { }
                if (link_ != null) link_.Dispose();
                channel_.Dispose();
                throw;
            }
            if (config.Reconnect)
            {
                supervisor_ = new Thread(Supervise) { IsBackground = true, Name = "hapticd supervisor" };
                supervisor_.Start();
            }
        }

        ~Client()
        {
            // Collected without Dispose: the server's lease ends the session; only the threads go.
            if (!closed_) StopThreads();
        }

        // ---- configuration ----

        private static Endpoint EndpointOf(ClientConfig config)
        {
            string address = config.ServerAddress ?? "";
            var endpoint = new Endpoint();
            if (address.StartsWith("https://")) { endpoint.Tls = true; address = address.Substring(8); }
            else if (address.StartsWith("http://")) address = address.Substring(7);
            address = address.TrimEnd('/');
            string host;
            int port;
            if (!SplitHostPort(address, out host, out port))
            {
                throw new HapticException(ErrorCode.InvalidArgument, "ClientConfig: ServerAddress: '" + config.ServerAddress +
                                          "' is not host:port with a port 1 to 65535");
            }
            endpoint.Host = host;
            endpoint.Port = port;
            endpoint.ServerName = config.TlsServerName ?? "";
            try
            {
                if (!string.IsNullOrEmpty(config.TlsCaFile))
                {
                    endpoint.Tls = true;
                    endpoint.TrustedCa = new X509Certificate2(config.TlsCaFile);
                }
            }
            catch (Exception e)
            {
                throw new HapticException(ErrorCode.InvalidArgument, "ClientConfig: TlsCaFile: cannot read '" + config.TlsCaFile + "': " + Endpoint.Innermost(e).Message);
            }
            if (!string.IsNullOrEmpty(config.TlsKeyFile))
            {
                throw new HapticException(ErrorCode.InvalidArgument, "ClientConfig: TlsKeyFile: a PEM private key is not read by the " +
                    "managed client: give TlsCertFile as PKCS#12 holding the key (openssl pkcs12 -export -in cert.pem -inkey key.pem " +
                    "-out client.p12) and leave TlsKeyFile empty");
            }
            if (!string.IsNullOrEmpty(config.TlsCertFile))
            {
                if (!endpoint.Tls) throw new HapticException(ErrorCode.InvalidArgument, "ClientConfig: TlsCertFile: a client certificate needs TLS (TlsCaFile)");
                try
                {
                    endpoint.ClientCertificate = new X509Certificate2(config.TlsCertFile, config.TlsCertPassword ?? "");
                }
                catch (Exception e)
                {
                    throw new HapticException(ErrorCode.InvalidArgument, "ClientConfig: TlsCertFile: cannot read '" + config.TlsCertFile +
                        "' as PKCS#12 with its key (" + Endpoint.Innermost(e).Message + ")");
                }
                if (!endpoint.ClientCertificate.HasPrivateKey)
                {
                    throw new HapticException(ErrorCode.InvalidArgument, "ClientConfig: TlsCertFile: '" + config.TlsCertFile + "' holds no private key");
                }
            }
            return endpoint;
        }

        internal static bool SplitHostPort(string address, out string host, out int port)
        {
            host = "";
            port = 0;
            int colon = address.LastIndexOf(':');
            if (colon <= 0) return false;
            host = address.Substring(0, colon);
            if (host.StartsWith("[") && host.EndsWith("]")) host = host.Substring(1, host.Length - 2);
            return host.Length > 0 && int.TryParse(address.Substring(colon + 1), out port) && port >= 1 && port <= 65535;
        }

        private static bool IsLoopback(string host)
        {
            if (host == "localhost") return true;
            IPAddress ip;
            return IPAddress.TryParse(host, out ip) && IPAddress.IsLoopback(ip);
        }

        private static void CheckConfig(ClientConfig config, Endpoint endpoint)
        {
            if (!string.IsNullOrEmpty(config.Token) && !endpoint.Tls && !IsLoopback(endpoint.Host))
            {
                if (!config.AllowPlaintextToken)
                {
                    // The C++ SDK's words (every client of the project says the same): tls is
                    // TlsCaFile here, allow_plaintext_token AllowPlaintextToken.
                    throw new HapticException(ErrorCode.InvalidArgument, "ClientConfig: token: would be sent in clear to '" +
                        config.ServerAddress + "', where anyone on the network can read it: give tls (TlsOptions with the server's CA), " +
                        "or set allow_plaintext_token on a network you trust");
                }
                Console.Error.WriteLine("haptic: warning: sending the bearer token in clear to '" + config.ServerAddress + "' (AllowPlaintextToken)");
            }
            if (string.IsNullOrEmpty(config.ClientName) || config.ClientName.Length > 64)
            {
                throw new HapticException(ErrorCode.InvalidArgument, "ClientConfig: ClientName: must be 1 to 64 characters");
            }
            if (config.RpcTimeoutMs == 0) throw new HapticException(ErrorCode.InvalidArgument, "ClientConfig: RpcTimeoutMs: must be positive");
            if (config.HeartbeatPeriodMs == 0) throw new HapticException(ErrorCode.InvalidArgument, "ClientConfig: HeartbeatPeriodMs: must be positive");
        }

        private static byte[] KeyOf(JsonObject opened)
        {
            var key = Convert.FromBase64String(opened.String("udp_key"));
            if (key.Length != 16) throw new HapticException(ErrorCode.Internal, "OpenSession: udp_key: " + key.Length + " bytes, not 16");
            return key;
        }

        /// <summary>Where datagrams go: UdpAddress if given, else the server's host at the port
        /// OpenSession named.</summary>
        private IPEndPoint UdpEndpoint(uint udpPort)
        {
            string host = endpoint_.Host;
            int port = (int)udpPort;
            if (!string.IsNullOrEmpty(config_.UdpAddress) && !SplitHostPort(config_.UdpAddress, out host, out port))
            {
                throw new HapticException(ErrorCode.InvalidArgument, "ClientConfig: UdpAddress: '" + config_.UdpAddress + "' is not host:port");
            }
            IPAddress ip;
            if (!IPAddress.TryParse(host, out ip))
            {
                try
                {
                    var addresses = Dns.GetHostAddresses(host);
                    ip = Array.Find(addresses, a => a.AddressFamily == AddressFamily.InterNetwork) ?? (addresses.Length > 0 ? addresses[0] : null);
                }
                catch (SocketException e)
                {
                    throw new HapticException(ErrorCode.Connection, "OpenSession: cannot resolve '" + host + "': " + e.Message);
                }
                if (ip == null) throw new HapticException(ErrorCode.Connection, "OpenSession: '" + host + "' has no address");
            }
            return new IPEndPoint(ip, port);
        }

        // ---- calls ----

        private List<KeyValuePair<string, string>> Headers()
        {
            var headers = new List<KeyValuePair<string, string>>(2);
            if (token_.Length > 0) headers.Add(new KeyValuePair<string, string>("Authorization", "Bearer " + token_));
            lock (identity_)
            {
                if (sessionSecret_.Length > 0) headers.Add(new KeyValuePair<string, string>("haptic-session-secret-bin", sessionSecret_));
            }
            return headers;
        }

        /// <summary>One unary call of haptic.v1.Haptic over the HTTP face: the reply's message, or
        /// HapticException with the gRPC code mapped and "name: " before the server's words.</summary>
        internal JsonObject Call(string name, JsonObject request, uint timeoutMs = 0)
        {
            var reply = channel_.Post("/haptic.v1.Haptic/" + name, Json.Write(request), Headers(),
                                      (int)Math.Min(int.MaxValue, timeoutMs > 0 ? timeoutMs : config_.RpcTimeoutMs), name);
            object parsed = null;
            try { parsed = Json.Parse(reply.Body); }
            catch (FormatException) { }
            var message = parsed as JsonObject;
            if (reply.Status == 200)
            {
                if (message == null) throw new HapticException(ErrorCode.Internal, name + ": the reply is not JSON: " + Clip(reply.Body));
                return message;
            }
            if (message != null && message.Has("code")) throw Refusal(name, message.String("code"), message.String("message"));
            throw new HapticException(reply.Status == 429 ? ErrorCode.ResourceExhausted : reply.Status == 413 ? ErrorCode.InvalidArgument : ErrorCode.Internal,
                                      name + ": HTTP " + reply.Status + ": " + Clip(reply.Body.Trim()));
        }

        private static string Clip(string text) { return text.Length > 200 ? text.Substring(0, 200) + "…" : text; }

        /// <summary>A Connect-style error as the SDK's (sdk/src/status_mapping.cpp).</summary>
        internal static HapticException Refusal(string call, string code, string text)
        {
            string message = call + ": " + text;
            switch (code)
            {
                case "unavailable": case "deadline_exceeded": case "canceled": return new HapticException(ErrorCode.Connection, message);
                case "invalid_argument": case "out_of_range": return new HapticException(ErrorCode.InvalidArgument, message);
                case "not_found": return new HapticException(ErrorCode.NotFound, message);
                case "permission_denied": return new HapticException(ErrorCode.PermissionDenied, message);
                case "unauthenticated": return new HapticException(ErrorCode.Unauthenticated, message);
                case "resource_exhausted": return new HapticException(ErrorCode.ResourceExhausted, message);
                case "failed_precondition":
                    return new HapticException(text.StartsWith("api_version:") ? ErrorCode.VersionMismatch : ErrorCode.FailedPrecondition, message);
            }
            return new HapticException(ErrorCode.Internal, message);
        }

        private JsonObject SessionRef() { return new JsonObject().Add("session_id", SessionId); }

        private JsonObject OpenSession()
        {
            var opened = Call("OpenSession", new JsonObject().Add("client_name", config_.ClientName).Add("api_version", ApiVersion)
                                                              .Add("device_index", config_.DeviceIndex));
            lock (identity_)
            {
                sessionId_ = opened.U64("session_id");
                sessionSecret_ = opened.String("session_secret");
            }
            deviceInfo_ = Conversions.DeviceInfoOf(opened.Object("device"));
            leaseTimeoutMs_ = opened.U32("lease_timeout_ms");
            return opened;
        }

        private void CloseSession()
        {
            if (SessionId == 0) return;
            try
            {
                Call("CloseSession", SessionRef());
            }
            catch (HapticException e)
            {
                // The server ended the session itself (an admin, a lease): nothing is left to close.
                if (e.Code != ErrorCode.NotFound && e.Code != ErrorCode.PermissionDenied) throw;
            }
        }

        /// <summary>The stream's link of an open client; FailedPrecondition once closed.</summary>
        private StateLink Link
        {
            get
            {
                RequireOpen();
                return link_;
            }
        }

        private void RequireOpen()
        {
            if (closed_) throw new HapticException(ErrorCode.FailedPrecondition, "Client: closed");
        }

        /// <summary>Ends the session; its objects and fields go with it.</summary>
        public void Dispose()
        {
            if (closed_) return;
            if (link_ != null && link_.OnReceiveThread || Thread.CurrentThread == supervisor_)
            {
                throw new HapticException(ErrorCode.FailedPrecondition, "Dispose: called from one of this client's own callbacks");
            }
            closed_ = true;
            StopThreads();
            try { CloseSession(); }
            catch (HapticException) { }  // the lease cleans up what a failed close leaves
            channel_.Dispose();
            GC.SuppressFinalize(this);
        }

        private void StopThreads()
        {
            stopSupervisor_.Set();
            if (supervisor_ != null && Thread.CurrentThread != supervisor_) supervisor_.Join();
            EndEvents();
            if (link_ != null) link_.Dispose();
        }

        // ---- the session ----

        public DeviceInfo DeviceInfo { get { RequireOpen(); return deviceInfo_; } }
        public ulong SessionId { get { lock (identity_) return sessionId_; } }
        public long LeaseTimeoutMs { get { return leaseTimeoutMs_; } }
        public ConnectionState ConnectionState { get { return (ConnectionState)Volatile.Read(ref connectionState_); } }

        /// <summary>Exceptions thrown by this client's callbacks (caught, so that none reaches its threads).</summary>
        public long CallbackExceptions { get { return Interlocked.Read(ref callbackExceptions_); } }

        private void CallbackFailed(Exception e)
        {
            if (Interlocked.Increment(ref callbackExceptions_) == 1)
            {
                Console.Error.WriteLine("hapticd: a callback threw (counted in Client.CallbackExceptions): " + e);
            }
        }

        // ---- state ----

        /// <summary>Waits up to timeoutMs for a sample newer than the last one returned: true and the
        /// newest in `state`, or false on timeout.</summary>
        public bool PollState(out State state, uint timeoutMs) { return Link.Poll(out state, timeoutMs); }

        /// <summary>Waits up to timeoutMs until a sample of tick >= `tick` has arrived.</summary>
        public bool WaitForTick(ulong tick, out State state, uint timeoutMs) { return Link.WaitForTick(tick, out state, timeoutMs); }

        /// <summary>Sets the state stream's decimation (every n-th tick; 0 stops it); for n > 0
        /// waits until the server knows this client's UDP address.</summary>
        public void Subscribe(uint decimation)
        {
            var link = Link;
            if (decimation > 0 && decimation_ == 0) link.NewSubscription();
            decimation_ = decimation;
            var request = SessionRef().Add("decimation", decimation);
            if (config_.LockstepFlowControl) request.Add("ack_window", link.AckWindowCapacity);
            long giveUp = SteadyClock.Ns() + config_.RpcTimeoutMs * 1000000L;
            for (;;)
            {
                var reply = Call("SubscribeState", request);
                link.AckWindow = reply.U32("ack_window");
                if (decimation == 0 || reply.Bool("udp_endpoint_known")) return;
                if (SteadyClock.Ns() > giveUp)
                {
                    throw new HapticException(ErrorCode.Connection, "SubscribeState: UDP heartbeats from this client do not reach the " +
                                              "server's data-plane port (a firewall or NAT dropping UDP?)");
                }
                link.SendHeartbeatSoon();
                Thread.Sleep(5);
            }
        }

        /// <summary>Calls `callback` on the client's receive thread with each newest State (null
        /// stops it, returning once a call in progress has). Keep it short; guard what it shares.</summary>
        public void OnState(Action<State> callback)
        {
            var link = Link;
            onState_ = callback;
            if (callback == null) { link.OnState(null); return; }
            link.OnState(state =>
            {
                try { var cb = onState_; if (cb != null) cb(state); }
                catch (Exception e) { CallbackFailed(e); }
            });
        }

        /// <summary>Calls `callback` on a thread of the client's with each server event from now on,
        /// starting with WatchStarted (null stops it). The server's refusal is thrown here.</summary>
        public void OnEvent(Action<Event> callback)
        {
            RequireOpen();
            EndEvents();
            onEvent_ = callback;
            if (callback == null) return;
            var watch = OpenWatch(e =>
            {
                try { var cb = onEvent_; if (cb != null) cb(e); }
                catch (Exception x) { CallbackFailed(x); }
            });
            lock (eventsGate_) events_ = watch;
        }

        private void EndEvents()
        {
            EventWatch watch;
            lock (eventsGate_) { watch = events_; events_ = null; }
            if (watch != null) watch.End();
        }

        /// <summary>Opens a WatchEvents stream over WebSocket and runs `deliver` on its thread
        /// with each event, WatchStarted first; throws the server's refusal.</summary>
        internal EventWatch OpenWatch(Action<Event> deliver)
        {
            var ws = WebSocketChannel.Open(endpoint_, "/haptic.v1.Haptic/WatchEvents", Headers(), (int)config_.RpcTimeoutMs, "WatchEvents");
            try
            {
                ws.SendText(Json.Write(new JsonObject().Add("request", SessionRef())));
                string reason;
                var first = ws.Receive(out reason);
                if (first == null) throw new HapticException(ErrorCode.Connection, "WatchEvents: the stream ended at once: " + reason);
                var message = Json.Parse(Encoding.UTF8.GetString(first)) as JsonObject ?? new JsonObject();
                if (message.Has("error"))
                {
                    var error = message.Object("error");
                    throw Refusal("WatchEvents", error.String("code"), error.String("message"));
                }
                return new EventWatch(ws, Conversions.EventOf(message.Object("event")), deliver);
            }
            catch
            {
                ws.Dispose();
                throw;
            }
        }

        /// <summary>Calls `callback` on the supervisor's thread when the connection is lost, when
        /// it resumes, and when it ends for good (null stops it).</summary>
        public void OnConnection(Action<ConnectionChange> callback) { onConnection_ = callback; }

        public ReceiveCounters ReceiveCounters { get { return Link.Counters; } }

        /// <summary>Heartbeats off: the client plays one that has vanished (its lease runs out).</summary>
        public void SetHeartbeatsEnabled(bool enabled)
        {
            heartbeatsEnabled_ = enabled;
            Link.HeartbeatsEnabled = enabled;
            if (enabled) link_.SendHeartbeatSoon();
        }

        /// <summary>The steady clock's now (ns), the clock of State's local times.</summary>
        public static long SteadyClockNs() { return SteadyClock.Ns(); }

        /// <summary>The server's time (s) at local steady-clock time `localNs`, or null before any sample.</summary>
        public double? ServerTimeAt(long localNs) { return Link.ServerTimeAt(localNs); }

        /// <summary>The server's time now (s), or null before any sample: a frame's time for Motion.</summary>
        public double? ServerTimeNow() { return ServerTimeAt(SteadyClockNs()); }

        public long? ClockOffsetNs { get { return Link.ClockOffsetNs; } }
        public double? ClockDrift { get { return Link.ClockDrift; } }

        // ---- objects and fields ----

        private ulong Generation { get { return (ulong)Interlocked.Read(ref generation_); } }

        /// <summary>CreateObject or CreateField (`call`, by the spec's kind), kept under a new key.</summary>
        private ItemHandle Create(object spec, string call)
        {
            RequireOpen();
            bool isObject;
            var message = Conversions.ToProto(spec, out isObject, call, "spec");
            var reply = isObject ? Call("CreateObject", SessionRef().Add("object", message))
                                 : Call("CreateField", SessionRef().Add("field", message));
            ulong key;
            lock (itemsGate_)
            {
                key = nextKey_++;
                items_[key] = new Item { IsObject = isObject, Message = message, ServerId = reply.U64("id") };
            }
            var stability = Conversions.StabilityOf(reply.Object("stability"), reply.Has("stability"));
            return isObject ? (ItemHandle)new ObjectHandle(this, key, Generation, stability) : new FieldHandle(this, key, Generation, stability);
        }

        public ObjectHandle AddWall(WallSpec s) { return (ObjectHandle)Create(s, "CreateObject"); }
        public ObjectHandle AddSphere(SphereSpec s) { return (ObjectHandle)Create(s, "CreateObject"); }
        public ObjectHandle AddBox(BoxSpec s) { return (ObjectHandle)Create(s, "CreateObject"); }
        public ObjectHandle AddCapsule(CapsuleSpec s) { return (ObjectHandle)Create(s, "CreateObject"); }
        public ObjectHandle AddTangentPlane(TangentPlaneSpec s) { return (ObjectHandle)Create(s, "CreateObject"); }
        public ObjectHandle AddMesh(MeshSpec mesh)
        {
            if (mesh == null) throw new HapticException(ErrorCode.InvalidArgument, "CreateObject: object.mesh: is null");
            return (ObjectHandle)Create(mesh, "CreateObject");
        }
        public FieldHandle AddField(SpringFieldSpec s) { return (FieldHandle)Create(s, "CreateField"); }
        public FieldHandle AddField(DistanceSpringSpec s) { return (FieldHandle)Create(s, "CreateField"); }
        public FieldHandle AddField(PotentialFieldSpec s) { return (FieldHandle)Create(s, "CreateField"); }
        public FieldHandle AddField(LinearFieldSpec s) { return (FieldHandle)Create(s, "CreateField"); }
        public FieldHandle AddField(ViscousFieldSpec s) { return (FieldHandle)Create(s, "CreateField"); }
        public FieldHandle AddField(DetentFieldSpec s) { return (FieldHandle)Create(s, "CreateField"); }
        public FieldHandle AddField(OrientationSpringSpec s) { return (FieldHandle)Create(s, "CreateField"); }
        public FieldHandle AddField(OrientationDetentSpec s) { return (FieldHandle)Create(s, "CreateField"); }

        /// <summary>The item's id on the server now; 0 if the client no longer holds it.</summary>
        internal ulong ServerIdOf(ulong key, ulong generation)
        {
            if (generation != Generation) return 0;
            lock (itemsGate_)
            {
                Item item;
                return items_.TryGetValue(key, out item) ? item.ServerId : 0;
            }
        }

        /// <summary>The item's server id, or NotFound naming `call` (an item a reconnection could
        /// not register again says why; a stale handle's item is gone).</summary>
        private ulong RequireServerId(ulong key, ulong generation, string call)
        {
            lock (itemsGate_)
            {
                Item item;
                if (generation != Generation || !items_.TryGetValue(key, out item))
                {
                    throw new HapticException(ErrorCode.NotFound, call + ": the item is no longer this client's (a scene applied or a reset since)");
                }
                if (item.ServerId == 0)
                {
                    throw new HapticException(ErrorCode.NotFound, call + ": the item was not registered again after a reconnection: " + item.LostReason);
                }
                return item.ServerId;
            }
        }

        internal StabilityReport UpdateItem(ItemHandle handle, object spec)
        {
            string call = handle.IsObject ? "UpdateObject" : "UpdateField";
            ulong key = handle.Live(call);
            RequireOpen();
            bool isObject;
            var message = Conversions.ToProto(spec, out isObject, call, "spec");
            ulong id = RequireServerId(key, handle.Generation, call);
            var reply = handle.IsObject ? Call(call, SessionRef().Add("object_id", id).Add("object", message))
                                        : Call(call, SessionRef().Add("field_id", id).Add("field", message));
            lock (itemsGate_)
            {
                Item item;
                if (items_.TryGetValue(key, out item)) item.Message = message;
            }
            if (handle.IsObject) return Conversions.StabilityOf(reply.Object("stability"), reply.Has("stability"));
            return new StabilityReport();  // UpdateField replies with nothing: an updated field's report is not known
        }

        internal void Remove(ulong key, ulong generation, bool isObject)
        {
            if (closed_ || generation != Generation) return;  // stale: its item is gone already
            ulong id;
            lock (itemsGate_)
            {
                Item item;
                if (!items_.TryGetValue(key, out item)) return;
                items_.Remove(key);
                id = item.ServerId;
            }
            if (id == 0) return;
            Call(isObject ? "DeleteObject" : "DeleteField", SessionRef().Add("id", id));
        }

        internal void Forget(ulong key) { lock (itemsGate_) items_.Remove(key); }

        // ---- scenes ----

        private static JsonObject SceneMessage(IList<object> items, string call, out List<bool> kinds)
        {
            var objects = new List<object>();
            var fields = new List<object>();
            kinds = new List<bool>();
            for (int i = 0; i < (items == null ? 0 : items.Count); ++i)
            {
                bool isObject;
                var message = Conversions.ToProto(items[i], out isObject, call, "items[" + i + "]");
                (isObject ? objects : fields).Add(message);
                kinds.Add(isObject);
            }
            return new JsonObject().Add("objects", objects).Add("fields", fields);
        }

        /// <summary>Replaces this session's whole scene with `items` (object and field specs in any
        /// order); all or nothing. Handles from earlier calls go stale.</summary>
        public AppliedScene ApplyScene(IList<object> items)
        {
            List<bool> kinds;
            var scene = SceneMessage(items, "ApplyScene", out kinds);
            return Apply(scene);
        }

        /// <summary>The same from a scene file (protobuf JSON of haptic.v1.Scene, as hapticd --scene reads).</summary>
        public AppliedScene ApplySceneFile(string path)
        {
            string text;
            try { text = File.ReadAllText(path); }
            catch (Exception e) { throw new HapticException(ErrorCode.InvalidArgument, "ApplySceneFile: path: cannot read '" + path + "': " + e.Message); }
            JsonObject scene;
            try { scene = Json.Parse(text) as JsonObject; }
            catch (FormatException e) { throw new HapticException(ErrorCode.InvalidArgument, "ApplySceneFile: " + path + ": " + e.Message); }
            if (scene == null) throw new HapticException(ErrorCode.InvalidArgument, "ApplySceneFile: " + path + ": not a JSON object");
            return Apply(scene);
        }

        private AppliedScene Apply(JsonObject scene)
        {
            RequireOpen();
            var reply = Call("ApplyScene", SessionRef().Add("scene", scene));
            var result = new AppliedScene();
            var objectIds = reply.Array("object_ids");
            var fieldIds = reply.Array("field_ids");
            var stability = reply.Array("object_stability");
            var objects = scene.Array("objects");
            var fields = scene.Array("fields");
            lock (itemsGate_)
            {
                items_.Clear();
                ulong generation = (ulong)Interlocked.Increment(ref generation_);
                for (int i = 0; i < objectIds.Count; ++i)
                {
                    ulong key = nextKey_++;
                    items_[key] = new Item { IsObject = true, Message = i < objects.Count ? objects[i] as JsonObject : null, ServerId = Json.ToU64(objectIds[i]) };
                    var report = Conversions.StabilityOf(i < stability.Count ? stability[i] as JsonObject ?? new JsonObject() : new JsonObject(), i < stability.Count);
                    result.Objects.Add(new ObjectHandle(this, key, generation, report));
                    result.Stability.Add(report);
                }
                for (int i = 0; i < fieldIds.Count; ++i)
                {
                    ulong key = nextKey_++;
                    items_[key] = new Item { IsObject = false, Message = i < fields.Count ? fields[i] as JsonObject : null, ServerId = Json.ToU64(fieldIds[i]) };
                    result.Fields.Add(new FieldHandle(this, key, generation, new StabilityReport()));
                }
            }
            return result;
        }

        /// <summary>`items` as a scene file (the JSON ApplySceneFile reads).</summary>
        public static string SceneJson(IList<object> items)
        {
            List<bool> kinds;
            return Json.Write(SceneMessage(items, "ApplyScene", out kinds));
        }

        /// <summary>This session's objects and fields as the server holds them; with allSessions, everyone's.</summary>
        public RegisteredScene Scene(bool allSessions = false)
        {
            RequireOpen();
            var reply = Call("GetScene", SessionRef().Add("all_sessions", allSessions));
            var scene = reply.Object("scene");
            var result = new RegisteredScene();
            foreach (var o in scene.Array("objects")) result.Objects.Add(Conversions.ObjectSpecOf(o as JsonObject ?? new JsonObject()));
            foreach (var f in scene.Array("fields")) result.Fields.Add(Conversions.FieldSpecOf(f as JsonObject ?? new JsonObject()));
            foreach (var id in reply.Array("object_ids")) result.ObjectIds.Add(Json.ToU64(id));
            foreach (var id in reply.Array("field_ids")) result.FieldIds.Add(Json.ToU64(id));
            foreach (var id in reply.Array("object_sessions")) result.ObjectSessions.Add(Json.ToU64(id));
            foreach (var id in reply.Array("field_sessions")) result.FieldSessions.Add(Json.ToU64(id));
            return result;
        }

        public ItemEnergy[] SceneEnergy()
        {
            var items = new List<ItemEnergy>();
            foreach (var i in Call("GetSceneEnergy", SessionRef()).Array("items"))
            {
                var e = i as JsonObject ?? new JsonObject();
                items.Add(new ItemEnergy { Id = e.U64("id"), SessionId = e.U64("session_id"), IsObject = e.Bool("is_object"),
                                           GivenToDevice = e.Double("given_to_device"), AbsorbedFromDevice = e.Double("absorbed_from_device") });
            }
            return items.ToArray();
        }

        public ObjectState[] ObjectStates()
        {
            var states = new List<ObjectState>();
            foreach (var i in Call("GetObjectStates", SessionRef()).Array("objects"))
            {
                var o = i as JsonObject ?? new JsonObject();
                states.Add(new ObjectState { Id = o.U64("id"), Position = Conversions.V(o.Object("position")), Velocity = Conversions.V(o.Object("velocity")) });
            }
            return states.ToArray();
        }

        // ---- the simulated operator, lockstep ----

        public void SetOperator(OperatorInput input)
        {
            if (input == null) throw new HapticException(ErrorCode.InvalidArgument, "SetOperator: input: is null");
            Call("SetOperator", SessionRef().Add("input", Conversions.OperatorJson(input)));
        }

        /// <summary>Lockstep servers only: runs `ticks` ticks; returns the last one's index.</summary>
        public ulong Step(uint ticks)
        {
            var link = Link;
            // As long as the same ticks take in real time, beyond RpcTimeoutMs: a slow reader slows a Step.
            double rate = deviceInfo_.LoopRateHz > 0 ? deviceInfo_.LoopRateHz : 1000.0;
            uint timeout = (uint)Math.Min(uint.MaxValue, config_.RpcTimeoutMs + Math.Ceiling(ticks * 1000.0 / rate));
            var reply = Call("Step", SessionRef().Add("ticks", ticks), timeout);
            NoteRun(reply.U64("run"));
            if (reply.Has("state")) link.Offer(Conversions.StateOf(reply.Object("state"), SteadyClock.Ns()));
            return reply.U64("tick");
        }

        /// <summary>A Step reply's run: if another client reset the server since, the ticks this
        /// client knew are forgotten before the reply's sample is offered.</summary>
        private void NoteRun(ulong run)
        {
            lock (runGate_)
            {
                if (run == knownRun_) return;
                knownRun_ = run;
            }
            link_.RestartTicks();
        }

        /// <summary>Lockstep servers with simulated devices only: puts the server back as it
        /// started; this session's items are gone (handles go stale) and ticks count from 1.</summary>
        public void Reset()
        {
            var link = Link;
            var reply = Call("Reset", SessionRef());
            lock (itemsGate_)
            {
                items_.Clear();
                Interlocked.Increment(ref generation_);
            }
            lock (runGate_) knownRun_ = reply.U64("run");
            link.RestartTicks();
        }

        // ---- administration ----

        public Stats Stats() { return Conversions.StatsOf(Call("GetStats", SessionRef())); }

        public SessionSummary[] Sessions()
        {
            var list = new List<SessionSummary>();
            foreach (var s in Call("ListSessions", SessionRef()).Array("sessions")) list.Add(Conversions.SessionOf(s as JsonObject ?? new JsonObject()));
            return list.ToArray();
        }

        public void KickSession(ulong sessionId, string reason = "")
        {
            Call("KickSession", SessionRef().Add("target_session_id", sessionId).Add("reason", reason ?? ""));
        }

        /// <summary>Starts the server's own recording (its recording_dir) under `name`.</summary>
        public RecordingStatus StartRecording(string name)
        {
            return Conversions.RecordingOf(Call("StartRecording", SessionRef().Add("name", name ?? "")));
        }

        public RecordingStatus StopRecording() { return Conversions.RecordingOf(Call("StopRecording", SessionRef())); }

        /// <summary>Starts recording what this client receives into a CSV file (docs/recorder.md).
        /// Refused (HapticException, InvalidArgument naming the field) for a bad path or an
        /// existing file; nothing is left behind then.</summary>
        public Recorder Record(RecorderOptions options)
        {
            if (options == null) throw new HapticException(ErrorCode.InvalidArgument, "record: options: is null");
            var link = Link;
            var recorder = new Recorder(options);
            try
            {
                if (options.Events)
                {
                    recorder.WatchEvents(OpenWatch(recorder.AddEvent));
                }
            }
            catch
            {
                recorder.Close();
                throw;
            }
            recorder.Attach(link, recorders_);
            return recorder;
        }

        // ---- the connection's supervision ----

        private void Announce(ConnectionChange change)
        {
            Volatile.Write(ref connectionState_, (int)change.State);
            Recorder[] recorders;
            lock (recorders_) recorders = recorders_.ToArray();
            foreach (var recorder in recorders) recorder.AddConnectionChange(change);
            try { var cb = onConnection_; if (cb != null) cb(change); }
            catch (Exception e) { CallbackFailed(e); }
        }

        private enum Probe { Alive, Unreachable, SessionGone, Ended }

        /// <summary>Probes a quiet connection every lease / 4 (20 to 500 ms); a failed probe is a
        /// loss, recovered with backoff: the same session if it still exists, else a new one with
        /// the items registered again, the stream and the events resumed (as the C++ SDK).</summary>
        private void Supervise()
        {
            int period = (int)Math.Min(500, Math.Max(20, leaseTimeoutMs_ / 4));
            while (!stopSupervisor_.WaitOne(period))
            {
                if (!heartbeatsEnabled_) continue;  // playing a vanished client: let the lease run out
                string why;
                var state = ProbeNow(out why);
                if (state == Probe.Ended)
                {
                    Announce(new ConnectionChange { State = ConnectionState.Ended, SessionId = SessionId, Reason = why });
                    return;
                }
                if (state != Probe.Alive && !Recover(why)) return;
            }
        }

        private Probe ProbeNow(out string why)
        {
            why = "";
            // Datagrams within half a lease: the server holds the session and reaches us.
            long heard = link_.LastHeardNs;
            if (heard != 0 && SteadyClock.Ns() - heard < leaseTimeoutMs_ * 500000L) return Probe.Alive;
            try
            {
                Call("GetDeviceInfo", SessionRef(), (uint)Math.Max(1, Math.Min(config_.RpcTimeoutMs, leaseTimeoutMs_ / 2)));
                return Probe.Alive;
            }
            catch (HapticException e)
            {
                why = e.Message;
                switch (e.Code)
                {
                    case ErrorCode.NotFound: why = "the server no longer knows session " + SessionId + ": " + e.Message; return Probe.SessionGone;
                    case ErrorCode.Connection: why = "the server does not answer: " + e.Message; return Probe.Unreachable;
                    case ErrorCode.PermissionDenied: case ErrorCode.Unauthenticated: return Probe.Ended;
                    default: return Probe.Alive;
                }
            }
        }

        private bool Recover(string why)
        {
            long lostAt = SteadyClock.Ns();
            Announce(new ConnectionChange { State = ConnectionState.Lost, SessionId = SessionId, Reason = why });
            long backoff = 0;
            bool gone = false;
            for (;;)
            {
                string nowWhy = "";
                var state = gone ? Probe.SessionGone : ProbeNow(out nowWhy);
                if (state == Probe.Ended)
                {
                    Announce(new ConnectionChange { State = ConnectionState.Ended, SessionId = SessionId, Reason = nowWhy });
                    return false;
                }
                var resumed = new ConnectionChange { State = ConnectionState.Resumed };
                bool done = state == Probe.Alive;
                if (state == Probe.SessionGone)
                {
                    gone = true;  // from here on only a new session helps
                    try
                    {
                        Reopen();
                        done = true;
                        resumed.NewSession = true;
                        lock (itemsGate_) foreach (var item in items_.Values) if (item.ServerId == 0) resumed.ItemsNotRestored++;
                    }
                    catch (HapticException e) { nowWhy = e.Message; }
                }
                if (done)
                {
                    resumed.SessionId = SessionId;
                    resumed.OutageMs = (SteadyClock.Ns() - lostAt) / 1000000L;
                    resumed.Reason = "after " + resumed.OutageMs + " ms";
                    if (decimation_ > 0 && resumed.NewSession)
                    {
                        link_.CountLost((ulong)(resumed.OutageMs * 1e-3 * deviceInfo_.LoopRateHz / decimation_));
                    }
                    link_.CountReconnect();
                    Announce(resumed);
                    return true;
                }
                long outage = (SteadyClock.Ns() - lostAt) / 1000000L;
                backoff = NextReconnectDelay(backoff, outage);
                if (stopSupervisor_.WaitOne((int)backoff)) return false;
            }
        }

        /// <summary>The C++ SDK's backoff (client_core.hpp): from the minimum, doubling, at most
        /// 100 ms through the first 10 s of a loss, then on to the maximum.</summary>
        private long NextReconnectDelay(long previous, long outageMs)
        {
            long min = Math.Max(1, config_.ReconnectBackoffMinMs), max = Math.Max(min, config_.ReconnectBackoffMaxMs);
            long next = previous == 0 ? min : previous * 2;
            long cap = outageMs < 10000 ? Math.Max(100, min) : max;
            return Math.Min(Math.Min(next, cap), max);
        }

        private void Reopen()
        {
            var opened = OpenSession();
            link_.Rebind(UdpEndpoint(opened.U32("udp_port")), opened.U64("session_id"), KeyOf(opened));
            lock (itemsGate_)
            {
                // Every item again, in the order made; one the new server refuses keeps its reason.
                foreach (var item in items_.Values)
                {
                    if (item.Message == null) continue;
                    try
                    {
                        var reply = item.IsObject ? Call("CreateObject", SessionRef().Add("object", item.Message))
                                                  : Call("CreateField", SessionRef().Add("field", item.Message));
                        item.ServerId = reply.U64("id");
                    }
                    catch (HapticException e)
                    {
                        item.ServerId = 0;
                        item.LostReason = e.Message;
                    }
                }
            }
            if (decimation_ > 0)
            {
                try { Subscribe(decimation_); }
                catch (HapticException) { }  // the stream stays off until Subscribe is called again
            }
            if (onEvent_ != null)
            {
                try { OnEvent(onEvent_); }
                catch (HapticException) { }
            }
            // And every recorder's events (the C++ SDK's resume_observer_watches).
            Recorder[] recorders;
            lock (recorders_) recorders = recorders_.ToArray();
            foreach (var recorder in recorders) recorder.WatchEventsAgain(OpenWatch);
        }
    }

    /// <summary>A WatchEvents stream's reading thread: hands each event to `deliver`.</summary>
    internal sealed class EventWatch
    {
        private readonly WebSocketChannel ws_;
        private readonly Thread thread_;

        internal EventWatch(WebSocketChannel ws, Event first, Action<Event> deliver)
        {
            ws_ = ws;
            thread_ = new Thread(() =>
            {
                deliver(first);
                for (;;)
                {
                    string reason;
                    var bytes = ws_.Receive(out reason);
                    if (bytes == null) return;
                    JsonObject message;
                    try { message = Json.Parse(Encoding.UTF8.GetString(bytes)) as JsonObject; }
                    catch (FormatException) { continue; }
                    if (message != null && message.Has("event")) deliver(Conversions.EventOf(message.Object("event")));
                }
            }) { IsBackground = true, Name = "hapticd events" };
            thread_.Start();
        }

        internal bool OnThread { get { return Thread.CurrentThread == thread_; } }

        /// <summary>Closes the stream and waits for its thread (unless called from it).</summary>
        internal void End()
        {
            ws_.Dispose();
            if (Thread.CurrentThread != thread_) thread_.Join();
        }
    }
}
