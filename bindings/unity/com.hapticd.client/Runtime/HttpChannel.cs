// The control plane's transport: HTTP/1.1 to hapticd's HTTP face (docs/http.md), over a socket
// and, with TLS, an SslStream, and the WebSocket the event stream comes on (RFC 6455, client side).
// Written on TcpClient and SslStream alone, which every .NET Standard 2.1 runtime has (Unity's
// Mono and IL2CPP on every platform, .NET): HttpClient and ClientWebSocket differ between them in
// how they take a private CA and a client certificate, and one connection kept alive is all a
// client needs.
using System;
using System.Collections.Generic;
using System.IO;
using System.Net.Security;
using System.Net.Sockets;
using System.Security.Authentication;
using System.Security.Cryptography;
using System.Security.Cryptography.X509Certificates;
using System.Text;
using System.Threading;

namespace Hapticd
{
    /// <summary>Where and how to connect: host, port, and the TLS settings of ClientConfig.</summary>
    internal sealed class Endpoint
    {
        internal string Host = "127.0.0.1";
        internal int Port;
        internal bool Tls;
        internal X509Certificate2 TrustedCa;          // with Tls: the CA the server's certificate must chain to
        internal X509Certificate2 ClientCertificate;  // mutual TLS
        internal string ServerName = "";              // the name the server's certificate must carry

        /// <summary>Opens a connection: a socket with Nagle off, and the TLS handshake over it if
        /// asked. Throws HapticException(Connection) saying what failed.</summary>
        internal Stream Connect(int timeoutMs, out TcpClient socket, string call)
        {
            socket = new TcpClient { NoDelay = true };
            try
            {
                var connecting = socket.ConnectAsync(Host, Port);
                if (!connecting.Wait(timeoutMs)) throw new TimeoutException("no connection within " + timeoutMs + " ms");
                socket.ReceiveTimeout = timeoutMs;
                socket.SendTimeout = timeoutMs;
                Stream stream = socket.GetStream();
                if (!Tls) return stream;
                string refused = null;
                var ssl = new SslStream(stream, false, (sender, certificate, chain, errors) =>
                {
                    refused = CheckServerCertificate(certificate, errors);
                    return refused == null;
                });
                var certificates = new X509CertificateCollection();
                if (ClientCertificate != null) certificates.Add(ClientCertificate);
                try
                {
                    ssl.AuthenticateAsClient(ServerName.Length > 0 ? ServerName : Host, certificates, SslProtocols.Tls12, false);
                }
                catch (Exception e)
                {
                    throw new HapticException(ErrorCode.Connection, call + ": TLS handshake with " + Host + ":" + Port +
                        " failed: " + (refused ?? Innermost(e).Message));
                }
                return ssl;
            }
            catch (HapticException)
            {
                socket.Close();
                throw;
            }
            catch (Exception e)
            {
                socket.Close();
                throw new HapticException(ErrorCode.Connection, call + ": cannot reach " + Host + ":" + Port + ": " + Innermost(e).Message);
            }
        }

        internal static Exception Innermost(Exception e)
        {
            while (e.InnerException != null) e = e.InnerException;
            return e;
        }

        /// <summary>null if the server's certificate chains to TrustedCa and names the server;
        /// else why not.</summary>
        private string CheckServerCertificate(X509Certificate certificate, SslPolicyErrors errors)
        {
            if (certificate == null) return "the server sent no certificate";
            if ((errors & SslPolicyErrors.RemoteCertificateNameMismatch) != 0)
            {
                return "the server's certificate does not name '" + (ServerName.Length > 0 ? ServerName : Host) + "' (TlsServerName)";
            }
            if (TrustedCa == null) return errors == SslPolicyErrors.None ? null : "the server's certificate is not trusted: " + errors;
            // The runtime's own chain check does not know the private CA: build the chain with it
            // and require that it ends there.
            using (var chain = new X509Chain())
            {
                chain.ChainPolicy.RevocationMode = X509RevocationMode.NoCheck;
                chain.ChainPolicy.VerificationFlags = X509VerificationFlags.AllowUnknownCertificateAuthority;
                chain.ChainPolicy.ExtraStore.Add(TrustedCa);
                var server = new X509Certificate2(certificate);
                if (!chain.Build(server)) return "the server's certificate does not verify: " + ChainStatus(chain);
                var root = chain.ChainElements[chain.ChainElements.Count - 1].Certificate;
                if (root.Thumbprint != TrustedCa.Thumbprint || chain.ChainElements.Count < 2 && server.Thumbprint != TrustedCa.Thumbprint)
                {
                    return "the server's certificate is not signed by the CA in TlsCaFile (" + TrustedCa.Subject + ")";
                }
            }
            return null;
        }

        private static string ChainStatus(X509Chain chain)
        {
            var parts = new List<string>();
            foreach (var s in chain.ChainStatus) parts.Add(s.StatusInformation.Trim());
            return string.Join("; ", parts);
        }
    }

    /// <summary>One kept-alive HTTP/1.1 connection for unary calls: POST path, a JSON body in, the
    /// status and body out. One call at a time (calls from several threads wait their turn).</summary>
    internal sealed class HttpChannel : IDisposable
    {
        private readonly Endpoint endpoint_;
        private readonly object gate_ = new object();
        private TcpClient socket_;
        private Stream stream_;
        private readonly byte[] buffer_ = new byte[16384];
        private int bufferStart_, bufferEnd_;
        private bool disposed_;

        internal HttpChannel(Endpoint endpoint) { endpoint_ = endpoint; }

        internal struct Reply
        {
            internal int Status;
            internal string Body;
        }

        /// <summary>POSTs `body` (JSON) to `path` with `headers`; the reply whatever its status.
        /// Throws HapticException(Connection) when no reply comes within timeoutMs.</summary>
        internal Reply Post(string path, string body, IList<KeyValuePair<string, string>> headers, int timeoutMs, string call)
        {
            var head = new StringBuilder(256);
            head.Append("POST ").Append(path).Append(" HTTP/1.1\r\nHost: ").Append(endpoint_.Host).Append(':').Append(endpoint_.Port)
                .Append("\r\nContent-Type: application/json\r\nAccept: application/json\r\n");
            foreach (var h in headers) head.Append(h.Key).Append(": ").Append(h.Value).Append("\r\n");
            byte[] payload = Encoding.UTF8.GetBytes(body);
            head.Append("Content-Length: ").Append(payload.Length).Append("\r\n\r\n");
            byte[] request = Encoding.ASCII.GetBytes(head.ToString());
            lock (gate_)
            {
                if (disposed_) throw new HapticException(ErrorCode.FailedPrecondition, call + ": the client is closed");
                // A kept connection the server has since closed (its idle deadline) fails before a
                // byte of reply: that request was not read, so it is sent once more on a fresh one.
                for (int attempt = 0; ; ++attempt)
                {
                    bool reused = stream_ != null;
                    bool replyStarted = false;
                    try
                    {
                        if (stream_ == null) Open(timeoutMs, call);
                        socket_.ReceiveTimeout = timeoutMs;
                        socket_.SendTimeout = timeoutMs;
                        stream_.Write(request, 0, request.Length);
                        stream_.Write(payload, 0, payload.Length);
                        stream_.Flush();
                        return ReadReply(ref replyStarted);
                    }
                    catch (HapticException)
                    {
                        Drop();
                        throw;
                    }
                    catch (Exception e)
                    {
                        Drop();
                        if (reused && !replyStarted && attempt == 0) continue;
                        var inner = Endpoint.Innermost(e);
                        string why = inner is SocketException && ((SocketException)inner).SocketErrorCode == SocketError.TimedOut ||
                                     inner is TimeoutException || inner is IOException && replyStarted
                            ? "no reply within " + timeoutMs + " ms" : inner.Message;
                        throw new HapticException(ErrorCode.Connection, call + ": " + endpoint_.Host + ":" + endpoint_.Port + ": " + why);
                    }
                }
            }
        }

        private void Open(int timeoutMs, string call)
        {
            TcpClient socket;
            stream_ = endpoint_.Connect(timeoutMs, out socket, call);
            socket_ = socket;
            bufferStart_ = bufferEnd_ = 0;
        }

        private void Drop()
        {
            if (stream_ != null) { try { stream_.Dispose(); } catch (Exception) { } }
            if (socket_ != null) socket_.Close();
            stream_ = null;
            socket_ = null;
        }

        private int ReadByte(ref bool started)
        {
            if (bufferStart_ == bufferEnd_)
            {
                bufferStart_ = 0;
                bufferEnd_ = stream_.Read(buffer_, 0, buffer_.Length);
                if (bufferEnd_ <= 0) { bufferEnd_ = 0; throw new IOException("the server closed the connection"); }
            }
            started = true;
            return buffer_[bufferStart_++];
        }

        private string ReadLine(ref bool started)
        {
            var line = new StringBuilder();
            for (;;)
            {
                int c = ReadByte(ref started);
                if (c == '\n') break;
                if (c != '\r') line.Append((char)c);
                if (line.Length > 16384) throw new IOException("a reply line over 16 KiB");
            }
            return line.ToString();
        }

        private void ReadExactly(byte[] into, int offset, int count, ref bool started)
        {
            while (count > 0)
            {
                if (bufferStart_ < bufferEnd_)
                {
                    int n = Math.Min(count, bufferEnd_ - bufferStart_);
                    Buffer.BlockCopy(buffer_, bufferStart_, into, offset, n);
                    bufferStart_ += n;
                    offset += n;
                    count -= n;
                    continue;
                }
                into[offset] = (byte)ReadByte(ref started);
                ++offset;
                --count;
            }
        }

        private const int MaxReplyBytes = 64 << 20;

        private Reply ReadReply(ref bool started)
        {
            string status = ReadLine(ref started);
            var parts = status.Split(' ');
            int code;
            if (parts.Length < 2 || !parts[0].StartsWith("HTTP/1.") || !int.TryParse(parts[1], out code))
            {
                throw new IOException("not an HTTP reply: '" + status + "'");
            }
            long length = -1;
            bool chunked = false, close = parts[0] == "HTTP/1.0";
            for (string line = ReadLine(ref started); line.Length > 0; line = ReadLine(ref started))
            {
                int colon = line.IndexOf(':');
                if (colon <= 0) continue;
                string name = line.Substring(0, colon).Trim().ToLowerInvariant();
                string value = line.Substring(colon + 1).Trim();
                if (name == "content-length") length = long.Parse(value);
                else if (name == "transfer-encoding" && value.ToLowerInvariant().Contains("chunked")) chunked = true;
                else if (name == "connection" && value.ToLowerInvariant() == "close") close = true;
            }
            byte[] body;
            if (chunked)
            {
                var all = new MemoryStream();
                for (;;)
                {
                    string size = ReadLine(ref started);
                    int semicolon = size.IndexOf(';');
                    int n = Convert.ToInt32(semicolon >= 0 ? size.Substring(0, semicolon) : size, 16);
                    if (n == 0) { while (ReadLine(ref started).Length > 0) { } break; }
                    if (all.Length + n > MaxReplyBytes) throw new IOException("a reply over 64 MiB");
                    var chunk = new byte[n];
                    ReadExactly(chunk, 0, n, ref started);
                    all.Write(chunk, 0, n);
                    ReadLine(ref started);
                }
                body = all.ToArray();
            }
            else if (length >= 0)
            {
                if (length > MaxReplyBytes) throw new IOException("a reply over 64 MiB");
                body = new byte[length];
                ReadExactly(body, 0, (int)length, ref started);
            }
            else
            {
                // Neither: the body runs to the connection's end.
                var all = new MemoryStream();
                try { for (;;) all.WriteByte((byte)ReadByte(ref started)); }
                catch (IOException) { }
                body = all.ToArray();
                close = true;
            }
            if (close) Drop();
            return new Reply { Status = code, Body = Encoding.UTF8.GetString(body) };
        }

        public void Dispose()
        {
            lock (gate_)
            {
                disposed_ = true;
                Drop();
            }
        }
    }

    /// <summary>A client WebSocket (RFC 6455) on its own connection: the upgrade, text messages
    /// out (masked, as a client must), messages in. Receive blocks; Close from another thread ends
    /// a Receive in progress.</summary>
    internal sealed class WebSocketChannel : IDisposable
    {
        private TcpClient socket_;
        private Stream stream_;
        private readonly object sendGate_ = new object();
        private volatile bool closed_;
        private readonly RandomNumberGenerator random_ = RandomNumberGenerator.Create();

        /// <summary>Opens ws(s)://endpoint/path with `headers` on the upgrade request. Throws
        /// HapticException: Connection when unreachable, or the server's refusal.</summary>
        internal static WebSocketChannel Open(Endpoint endpoint, string path, IList<KeyValuePair<string, string>> headers,
                                              int timeoutMs, string call)
        {
            var ws = new WebSocketChannel();
            ws.stream_ = endpoint.Connect(timeoutMs, out ws.socket_, call);
            try
            {
                var nonce = new byte[16];
                ws.random_.GetBytes(nonce);
                string key = Convert.ToBase64String(nonce);
                var head = new StringBuilder();
                head.Append("GET ").Append(path).Append(" HTTP/1.1\r\nHost: ").Append(endpoint.Host).Append(':').Append(endpoint.Port)
                    .Append("\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Key: ")
                    .Append(key).Append("\r\n");
                foreach (var h in headers) head.Append(h.Key).Append(": ").Append(h.Value).Append("\r\n");
                head.Append("\r\n");
                var request = Encoding.ASCII.GetBytes(head.ToString());
                ws.stream_.Write(request, 0, request.Length);
                ws.stream_.Flush();
                string status = ws.ReadLine();
                string accept = "";
                for (string line = ws.ReadLine(); line.Length > 0; line = ws.ReadLine())
                {
                    int colon = line.IndexOf(':');
                    if (colon > 0 && line.Substring(0, colon).Trim().ToLowerInvariant() == "sec-websocket-accept") accept = line.Substring(colon + 1).Trim();
                }
                string expected;
                using (var sha1 = SHA1.Create())
                {
                    expected = Convert.ToBase64String(sha1.ComputeHash(Encoding.ASCII.GetBytes(key + "258EAFA5-E914-47DA-95CA-C5AB0DC85B11")));
                }
                if (!status.StartsWith("HTTP/1.1 101")) throw new HapticException(ErrorCode.Connection, call + ": the server declined the WebSocket: " + status);
                if (accept != expected) throw new HapticException(ErrorCode.Connection, call + ": the server's WebSocket handshake does not answer ours");
                ws.socket_.ReceiveTimeout = 0;  // a stream may be quiet for long
                return ws;
            }
            catch (HapticException)
            {
                ws.Dispose();
                throw;
            }
            catch (Exception e)
            {
                ws.Dispose();
                throw new HapticException(ErrorCode.Connection, call + ": WebSocket upgrade failed: " + Endpoint.Innermost(e).Message);
            }
        }

        private string ReadLine()
        {
            var line = new StringBuilder();
            for (;;)
            {
                int c = stream_.ReadByte();
                if (c < 0) throw new IOException("the server closed the connection");
                if (c == '\n') return line.ToString();
                if (c != '\r') line.Append((char)c);
                if (line.Length > 16384) throw new IOException("a reply line over 16 KiB");
            }
        }

        internal void SendText(string text) { Send(0x1, Encoding.UTF8.GetBytes(text)); }

        private void Send(int opcode, byte[] payload)
        {
            var frame = new MemoryStream(payload.Length + 14);
            frame.WriteByte((byte)(0x80 | opcode));
            if (payload.Length < 126) frame.WriteByte((byte)(0x80 | payload.Length));
            else if (payload.Length <= 0xffff) { frame.WriteByte(0x80 | 126); frame.WriteByte((byte)(payload.Length >> 8)); frame.WriteByte((byte)payload.Length); }
            else { frame.WriteByte(0x80 | 127); for (int i = 7; i >= 0; --i) frame.WriteByte((byte)((long)payload.Length >> (8 * i))); }
            var mask = new byte[4];
            random_.GetBytes(mask);
            frame.Write(mask, 0, 4);
            for (int i = 0; i < payload.Length; ++i) frame.WriteByte((byte)(payload[i] ^ mask[i & 3]));
            var bytes = frame.ToArray();
            lock (sendGate_)
            {
                stream_.Write(bytes, 0, bytes.Length);
                stream_.Flush();
            }
        }

        private void Fill(byte[] into, int count)
        {
            for (int at = 0; at < count;)
            {
                int n = stream_.Read(into, at, count - at);
                if (n <= 0) throw new IOException("the server closed the connection");
                at += n;
            }
        }

        private const long MaxMessageBytes = 16 << 20;

        /// <summary>The next message's payload (text as UTF-8), or null once the stream has ended
        /// (closed by either side; `closeReason` then says why, if the server said).</summary>
        internal byte[] Receive(out string closeReason)
        {
            closeReason = "";
            var message = new MemoryStream();
            var head = new byte[8];
            try
            {
                for (;;)
                {
                    Fill(head, 2);
                    bool fin = (head[0] & 0x80) != 0;
                    int opcode = head[0] & 0x0f;
                    long length = head[1] & 0x7f;
                    if (length == 126) { Fill(head, 2); length = (head[0] << 8) | head[1]; }
                    else if (length == 127) { Fill(head, 8); length = 0; for (int i = 0; i < 8; ++i) length = (length << 8) | head[i]; }
                    if (length < 0 || message.Length + length > MaxMessageBytes) throw new IOException("a WebSocket message over 16 MiB");
                    var payload = new byte[length];
                    Fill(payload, (int)length);
                    if (opcode == 0x8)
                    {
                        if (payload.Length > 2) closeReason = Encoding.UTF8.GetString(payload, 2, payload.Length - 2);
                        try { Send(0x8, payload.Length >= 2 ? new[] { payload[0], payload[1] } : new byte[0]); } catch (Exception) { }
                        Dispose();
                        return null;
                    }
                    if (opcode == 0x9) { Send(0xA, payload); continue; }  // ping: pong
                    if (opcode == 0xA) continue;
                    message.Write(payload, 0, payload.Length);
                    if (fin) return message.ToArray();
                }
            }
            catch (Exception e)
            {
                if (!closed_ && closeReason.Length == 0) closeReason = Endpoint.Innermost(e).Message;
                Dispose();
                return null;
            }
        }

        internal bool Closed { get { return closed_; } }

        public void Dispose()
        {
            closed_ = true;
            if (stream_ != null) { try { stream_.Dispose(); } catch (Exception) { } }
            if (socket_ != null) socket_.Close();
        }
    }
}
